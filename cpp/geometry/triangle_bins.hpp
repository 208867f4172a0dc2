// TriangleBins: a sparse grid of triangles (their bounding boxes grown by a margin), for the
// triangles near a point or a box. Used by mesh walls (neighbour lists), by insertion (wall
// avoidance) and by closed-mesh regions (distance to the surface).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/types.hpp"

namespace grainscale {

class TriangleBins {
 public:
  // Bins the triangles `which` (all when empty) of the mesh (vertices, triangles) into cells of
  // at least `min_cell`; each triangle enters every cell its bounding box grown by `margin`
  // overlaps.
  void build(const std::vector<Vec3>& vertices, const std::vector<std::array<int, 3>>& triangles,
             const std::vector<int>& which, Real margin, Real min_cell);
  // Triangles whose grown bounding box may contain x (each once, ascending cell entry order).
  void candidates(const Vec3& x, std::vector<int>& out) const;
  // Triangles whose grown bounding box may overlap the box [lo, hi]; sorted, each once.
  void candidates(const Vec3& lo, const Vec3& hi, std::vector<int>& out) const;
  bool empty() const { return cell_keys_.empty(); }

 private:
  // Cell of coordinate x on axis a, clamped to the grid.
  std::int64_t cell_on(int a, Real x) const;
  Vec3 origin_ = Vec3::Zero();
  Real inv_cell_ = 0;
  std::array<std::int64_t, 3> dims_{0, 0, 0};
  std::vector<std::int64_t> cell_keys_;  // sorted cell ids of the (cell, triangle) entries
  std::vector<int> cell_triangles_;      // triangle of each entry
};

}  // namespace grainscale
