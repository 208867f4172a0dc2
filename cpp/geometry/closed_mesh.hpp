// ClosedMesh: the solid bounded by a closed triangle surface (e.g. an STL part), as a region to
// pack. Vertices with identical coordinates are merged, then the surface must be closed and
// consistently oriented: every edge is shared by exactly two triangles that traverse it in
// opposite directions. Self-intersections are not detected.
//
// Volume: divergence theorem, V = |sum_t a_t . (b_t x c_t)| / 6 (either orientation).
// Inside: parity of the crossings of the ray from x along +x (Jordan-Brouwer). A ray through an
// edge or a vertex is decided as if the ray were shifted by (0, e, e^2), e -> 0+ (simulation of
// simplicity, Edelsbrunner & Muecke, ACM TOG 9, 1990): each edge's side is computed once in a
// canonical vertex order, so a crossing at a shared edge or vertex counts exactly once where the
// surface passes through and zero or two times where it folds back. A point on the surface itself
// may count either way (packing asks for a distance >= r > 0 from the surface).
// Distance to the surface: nearest triangle among the bins around the query.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "geometry/triangle_bins.hpp"
#include "geometry/triangle_mesh.hpp"

namespace grainscale {

class ClosedMesh {
 public:
  // Throws InvalidArgument (naming `what`) unless the surface is closed and consistently oriented.
  ClosedMesh(const std::vector<Vec3>& vertices, const std::vector<std::array<int, 3>>& triangles,
             const std::string& what);

  Real volume() const { return volume_; }
  void bounds(Vec3& lo, Vec3& hi) const {
    lo = lo_;
    hi = hi_;
  }
  bool inside(const Vec3& x) const;
  // Whether some point of the surface is nearer than r to x.
  bool near_surface(const Vec3& x, Real r) const;
  const TriangleMesh& mesh() const { return mesh_; }

 private:
  bool ray_crosses(int t, const Vec3& x) const;
  TriangleMesh mesh_;      // merged vertices
  TriangleBins bins_;      // 3-D, for distances
  TriangleBins ray_bins_;  // triangles binned by their (y, z) extent (x flattened), for rays
  Real volume_ = 0;
  Vec3 lo_ = Vec3::Zero(), hi_ = Vec3::Zero();
  mutable std::vector<int> scratch_;  // query buffer: one thread per ClosedMesh
};

}  // namespace grainscale
