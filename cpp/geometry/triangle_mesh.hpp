// TriangleMesh: a wall made of triangles (STL data handed over from Python), with a sparse
// grid of triangles for neighbour search and the closest-point query that tells which feature
// (face, edge, vertex) of a triangle a sphere touches.
//
// Closest point on a triangle: Voronoi-region test of Ericson, Real-Time Collision Detection
// (2005), section 5.1.5.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/types.hpp"

namespace grainscale {

struct TriangleHit {
  Vec3 point;   // closest point on the triangle
  int feature;  // 0 face, 1 edge, 2 vertex
  int a, b;     // mesh vertex ids: edge (a < b) or vertex (a, -1); face (-1, -1)
};

class TriangleMesh {
 public:
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;

  // Closest point of triangle t to x, with the feature it lies on.
  TriangleHit closest(int t, const Vec3& x) const;
  // Bins triangles (bounding boxes grown by `margin`) into cells of at least `min_cell`.
  void build_bins(Real margin, Real min_cell);
  // Triangles whose grown bounding box may contain x (valid until the mesh moves by more than
  // the margin allows; the level rebuilds bins with its lists).
  void candidates(const Vec3& x, std::vector<int>& out) const;
  // Largest distance of a vertex from `origin` (bounds the motion of a rotating mesh).
  Real radius_about(const Vec3& origin) const;

 private:
  Vec3 origin_ = Vec3::Zero();
  Real inv_cell_ = 0;
  std::array<std::int64_t, 3> dims_{0, 0, 0};
  std::vector<std::int64_t> cell_keys_;  // sorted cell ids of the (cell, triangle) entries
  std::vector<int> cell_triangles_;      // triangle of each entry
};

}  // namespace grainscale
