#include "geometry/triangle_bins.hpp"

#include <algorithm>
#include <cmath>

namespace grainscale {

std::int64_t TriangleBins::cell_on(int a, Real x) const {
  const Real u = std::floor((x - origin_[a]) * inv_cell_);
  return static_cast<std::int64_t>(std::clamp<Real>(u, 0, static_cast<Real>(dims_[a] - 1)));
}

void TriangleBins::build(const std::vector<Vec3>& vertices,
                         const std::vector<std::array<int, 3>>& triangles,
                         const std::vector<int>& which, Real margin, Real min_cell) {
  cell_keys_.clear();
  cell_triangles_.clear();
  const bool all = which.empty();
  const std::size_t n = all ? triangles.size() : which.size();
  if (n == 0) return;
  auto triangle = [&](std::size_t k) { return all ? static_cast<int>(k) : which[k]; };
  auto box_of = [&](int t, Vec3& tlo, Vec3& thi) {
    tlo = thi = vertices[triangles[t][0]];
    for (int k = 1; k < 3; ++k) {
      tlo = tlo.cwiseMin(vertices[triangles[t][k]]);
      thi = thi.cwiseMax(vertices[triangles[t][k]]);
    }
  };
  Vec3 lo, hi, tlo, thi;
  box_of(triangle(0), lo, hi);
  std::vector<Real> extents;
  extents.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    box_of(triangle(k), tlo, thi);
    lo = lo.cwiseMin(tlo);
    hi = hi.cwiseMax(thi);
    extents.push_back((thi - tlo).maxCoeff());
  }
  lo.array() -= margin;
  hi.array() += margin;
  // Cell edge: at least min_cell and the median triangle size, and coarse enough that the grid
  // stays near 2e5 cells for a mesh much larger than its particles.
  std::nth_element(extents.begin(), extents.begin() + extents.size() / 2, extents.end());
  const Vec3 size = hi - lo;
  const Real cell = std::max({min_cell, extents[extents.size() / 2], std::cbrt(size.prod() / 2e5),
                              size.maxCoeff() / 4096});
  origin_ = lo;
  inv_cell_ = 1 / cell;
  for (int a = 0; a < 3; ++a)
    dims_[a] = std::max<std::int64_t>(1, static_cast<std::int64_t>(size[a] * inv_cell_) + 1);
  std::vector<std::pair<std::int64_t, int>> entries;
  for (std::size_t k = 0; k < n; ++k) {
    const int t = triangle(k);
    box_of(t, tlo, thi);
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

void TriangleBins::candidates(const Vec3& x, std::vector<int>& out) const {
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

void TriangleBins::candidates(const Vec3& lo, const Vec3& hi, std::vector<int>& out) const {
  out.clear();
  if (cell_keys_.empty()) return;
  std::int64_t c0[3], c1[3];
  for (int a = 0; a < 3; ++a) {
    // A box entirely outside the grid meets no grown triangle box.
    if (hi[a] < origin_[a] || (lo[a] - origin_[a]) * inv_cell_ >= static_cast<Real>(dims_[a]))
      return;
    c0[a] = cell_on(a, lo[a]);
    c1[a] = cell_on(a, hi[a]);
  }
  for (std::int64_t z = c0[2]; z <= c1[2]; ++z)
    for (std::int64_t y = c0[1]; y <= c1[1]; ++y)
      for (std::int64_t x = c0[0]; x <= c1[0]; ++x) {
        const std::int64_t key = x + dims_[0] * (y + dims_[1] * z);
        auto range = std::equal_range(cell_keys_.begin(), cell_keys_.end(), key);
        for (auto it = range.first; it != range.second; ++it)
          out.push_back(cell_triangles_[it - cell_keys_.begin()]);
      }
  if (c0[0] != c1[0] || c0[1] != c1[1] || c0[2] != c1[2]) {
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }
}

}  // namespace grainscale
