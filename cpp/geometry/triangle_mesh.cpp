#include "geometry/triangle_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace grainscale {

TriangleHit TriangleMesh::closest(int t, const Vec3& p) const {
  const auto& tri = triangles[t];
  const Vec3& a = vertices[tri[0]];
  const Vec3& b = vertices[tri[1]];
  const Vec3& c = vertices[tri[2]];
  auto edge = [&](int i, int j, const Vec3& q) {
    return TriangleHit{q, 1, std::min(tri[i], tri[j]), std::max(tri[i], tri[j])};
  };
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const Real d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {a, 2, tri[0], -1};
  const Vec3 bp = p - b;
  const Real d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {b, 2, tri[1], -1};
  const Real vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return edge(0, 1, a + (d1 / (d1 - d3)) * ab);
  const Vec3 cp = p - c;
  const Real d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {c, 2, tri[2], -1};
  const Real vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return edge(0, 2, a + (d2 / (d2 - d6)) * ac);
  const Real va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return edge(1, 2, b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b));
  const Real denom = 1 / (va + vb + vc);
  return {a + ab * (vb * denom) + ac * (vc * denom), 0, -1, -1};
}

void TriangleMesh::build_bins(Real margin, Real min_cell) {
  cell_keys_.clear();
  cell_triangles_.clear();
  if (triangles.empty()) return;
  Vec3 lo = vertices[triangles[0][0]], hi = lo;
  std::vector<Real> extents;
  extents.reserve(triangles.size());
  for (const auto& t : triangles) {
    Vec3 tlo = vertices[t[0]], thi = tlo;
    for (int k = 1; k < 3; ++k) {
      tlo = tlo.cwiseMin(vertices[t[k]]);
      thi = thi.cwiseMax(vertices[t[k]]);
    }
    lo = lo.cwiseMin(tlo);
    hi = hi.cwiseMax(thi);
    extents.push_back((thi - tlo).maxCoeff());
  }
  lo.array() -= margin;
  hi.array() += margin;
  // Cell edge: at least the pair cut-off and the median triangle size, and coarse enough that
  // the grid stays near 2e5 cells for a mesh much larger than its particles.
  std::nth_element(extents.begin(), extents.begin() + extents.size() / 2, extents.end());
  const Vec3 size = hi - lo;
  Real cell = std::max({min_cell, extents[extents.size() / 2], std::cbrt(size.prod() / 2e5),
                        size.maxCoeff() / 4096});
  origin_ = lo;
  inv_cell_ = 1 / cell;
  for (int a = 0; a < 3; ++a)
    dims_[a] = std::max<std::int64_t>(1, static_cast<std::int64_t>(size[a] * inv_cell_) + 1);
  std::vector<std::pair<std::int64_t, int>> entries;
  for (int t = 0; t < static_cast<int>(triangles.size()); ++t) {
    Vec3 tlo = vertices[triangles[t][0]], thi = tlo;
    for (int k = 1; k < 3; ++k) {
      tlo = tlo.cwiseMin(vertices[triangles[t][k]]);
      thi = thi.cwiseMax(vertices[triangles[t][k]]);
    }
    std::array<std::int64_t, 3> c0, c1;
    for (int a = 0; a < 3; ++a) {
      c0[a] = std::clamp<std::int64_t>(
          static_cast<std::int64_t>((tlo[a] - margin - origin_[a]) * inv_cell_), 0, dims_[a] - 1);
      c1[a] = std::clamp<std::int64_t>(
          static_cast<std::int64_t>((thi[a] + margin - origin_[a]) * inv_cell_), 0, dims_[a] - 1);
    }
    for (std::int64_t z = c0[2]; z <= c1[2]; ++z)
      for (std::int64_t y = c0[1]; y <= c1[1]; ++y)
        for (std::int64_t x = c0[0]; x <= c1[0]; ++x)
          entries.emplace_back(x + dims_[0] * (y + dims_[1] * z), t);
  }
  std::sort(entries.begin(), entries.end());
  cell_keys_.reserve(entries.size());
  cell_triangles_.reserve(entries.size());
  for (const auto& [key, t] : entries) {
    cell_keys_.push_back(key);
    cell_triangles_.push_back(t);
  }
}

void TriangleMesh::candidates(const Vec3& x, std::vector<int>& out) const {
  out.clear();
  std::int64_t c[3];
  for (int a = 0; a < 3; ++a) {
    const Real u = (x[a] - origin_[a]) * inv_cell_;
    if (!(u >= 0) || u >= static_cast<Real>(dims_[a])) return;  // outside every grown box
    c[a] = static_cast<std::int64_t>(u);
  }
  const std::int64_t key = c[0] + dims_[0] * (c[1] + dims_[1] * c[2]);
  auto range = std::equal_range(cell_keys_.begin(), cell_keys_.end(), key);
  for (auto it = range.first; it != range.second; ++it)
    out.push_back(cell_triangles_[it - cell_keys_.begin()]);
}

Real TriangleMesh::radius_about(const Vec3& origin) const {
  Real r2 = 0;
  for (const Vec3& v : vertices) r2 = std::max(r2, (v - origin).squaredNorm());
  return std::sqrt(r2);
}

}  // namespace grainscale
