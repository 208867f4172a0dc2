// TriangleMesh: a wall made of triangles (STL data handed over from Python), with a sparse
// grid of triangles for neighbour search and the closest-point query that tells which feature
// (face, edge, vertex) of a triangle a sphere touches.
//
// Closest point on a triangle: Voronoi-region test of Ericson, Real-Time Collision Detection
// (2005), section 5.1.5.
#pragma once

#include <array>
#include <vector>

#include "core/types.hpp"
#include "geometry/triangle_bins.hpp"

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
  void build_bins(Real margin, Real min_cell) {
    bins_.build(vertices, triangles, {}, margin, min_cell);
  }
  // Triangles whose grown bounding box may contain x (valid until the mesh moves by more than
  // the margin allows; the level rebuilds bins with its lists).
  void candidates(const Vec3& x, std::vector<int>& out) const { bins_.candidates(x, out); }
  // Largest distance of a vertex from `origin` (bounds the motion of a rotating mesh).
  Real radius_about(const Vec3& origin) const;

 private:
  TriangleBins bins_;
};

}  // namespace grainscale
