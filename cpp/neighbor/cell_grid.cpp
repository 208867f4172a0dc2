#include "neighbor/cell_grid.hpp"

#include <algorithm>
#include <cmath>

namespace grainscale {

void CellGrid::build(const Vec3* x, Index n, Real min_cell, std::size_t max_cells) {
  Vec3 lo = Vec3::Constant(0), hi = Vec3::Constant(0);
  if (n > 0) {
    lo = hi = x[0];
    for (Index i = 1; i < n; ++i) {
      lo = lo.cwiseMin(x[i]);
      hi = hi.cwiseMax(x[i]);
    }
  }
  Real edge = min_cell;
  const Vec3 extent = hi - lo;
  auto count = [&](Real e) {
    std::array<int, 3> d;
    for (int a = 0; a < 3; ++a)
      d[a] = std::max(1, static_cast<int>(std::min<Real>(std::floor(extent[a] / e), 1 << 20)));
    return d;
  };
  dims = count(edge);
  max_cells = std::max<std::size_t>(max_cells, 1);
  while (static_cast<std::size_t>(dims[0]) * dims[1] * dims[2] > max_cells) {
    edge *= 2;
    dims = count(edge);
  }
  origin_ = lo;
  for (int a = 0; a < 3; ++a) inv_edge_[a] = extent[a] > 0 ? dims[a] / extent[a] : 0;

  const int nc = n_cells();
  cell_of.resize(n);
  cell_start.assign(nc + 1, 0);
  for (Index i = 0; i < n; ++i) {
    int c[3];
    for (int a = 0; a < 3; ++a)
      c[a] = std::min(dims[a] - 1, static_cast<int>((x[i][a] - origin_[a]) * inv_edge_[a]));
    const int id = cell_id(c[0], c[1], c[2]);
    cell_of[i] = id;
    ++cell_start[id + 1];
  }
  for (int c = 0; c < nc; ++c) cell_start[c + 1] += cell_start[c];
  particles.resize(n);
  fill_.assign(cell_start.begin(), cell_start.end() - 1);
  for (Index i = 0; i < n; ++i) particles[fill_[cell_of[i]]++] = i;
}

std::array<int, 3> CellGrid::reach(Real cutoff) const {
  // |floor(a) - floor(b)| <= ceil(|a - b|) for cell coordinates a, b (in cell edges).
  std::array<int, 3> r;
  for (int a = 0; a < 3; ++a)
    r[a] = std::min(dims[a] - 1, static_cast<int>(std::ceil(cutoff * inv_edge_[a])));
  return r;
}

void CellGrid::renumber_sorted() {
  const int nc = n_cells();
  for (int c = 0; c < nc; ++c)
    for (Index k = cell_start[c]; k < cell_start[c + 1]; ++k) {
      particles[k] = k;
      cell_of[k] = c;
    }
}

}  // namespace grainscale
