#include "insert/wall_clearance.hpp"

#include "geometry/segment_crossing.hpp"
#include "geometry/wall_distance.hpp"

namespace grainscale {

WallClearance::WallClearance(const std::vector<Wall>& walls, const Vec3& lo, const Vec3& hi,
                             Real max_radius) {
  const Vec3 grown_lo = lo.array() - max_radius, grown_hi = hi.array() + max_radius;
  std::vector<int> near;
  for (const Wall& w : walls) {
    if (w.shape != WallShape::Mesh) {
      simple_.push_back(&w);
      continue;
    }
    const TriangleMesh& m = *w.mesh;
    near.clear();
    for (int t = 0; t < static_cast<int>(m.triangles.size()); ++t) {
      Vec3 tlo = m.vertices[m.triangles[t][0]], thi = tlo;
      for (int k = 1; k < 3; ++k) {
        tlo = tlo.cwiseMin(m.vertices[m.triangles[t][k]]);
        thi = thi.cwiseMax(m.vertices[m.triangles[t][k]]);
      }
      if ((thi.array() >= grown_lo.array()).all() && (tlo.array() <= grown_hi.array()).all())
        near.push_back(t);
    }
    if (near.empty()) continue;
    meshes_.push_back({&m, TriangleBins()});
    meshes_.back().bins.build(m.vertices, m.triangles, near, max_radius, 2 * max_radius);
  }
}

bool WallClearance::clear(const Vec3& x, Real r) const {
  for (const Wall* w : simple_)
    if (wall_distance(*w, x) < r) return false;
  for (const MeshPart& part : meshes_) {
    part.bins.candidates(x, scratch_);
    if (mesh_distance(*part.mesh, scratch_, x, r) < r) return false;
  }
  return true;
}

bool WallClearance::blocks(const Vec3& x, Real reach, Real r) const {
  for (const Wall* w : simple_)
    if (wall_distance_bound(*w, x, reach) < r) return true;
  // The unsigned distance to a mesh is 1-Lipschitz; candidates at x hold every triangle within
  // max_radius >= r - reach of it.
  for (const MeshPart& part : meshes_) {
    part.bins.candidates(x, scratch_);
    if (mesh_distance(*part.mesh, scratch_, x, r - reach) + reach < r) return true;
  }
  return false;
}

bool WallClearance::separates(const Vec3& a, const Vec3& b) const {
  for (const Wall* w : simple_)
    if (segment_crosses(*w, a, b)) return true;
  for (const MeshPart& part : meshes_) {
    part.bins.candidates(a.cwiseMin(b), a.cwiseMax(b), scratch_);
    const TriangleMesh& m = *part.mesh;
    for (int t : scratch_) {
      const auto& tri = m.triangles[t];
      if (segment_crosses_triangle(a, b, m.vertices[tri[0]], m.vertices[tri[1]],
                                   m.vertices[tri[2]]))
        return true;
    }
  }
  return false;
}

}  // namespace grainscale
