#include "insert/centre_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "state/periodic_images.hpp"

namespace grainscale {

CentreGrid::CentreGrid(const Vec3& lo, const Vec3& hi, Real reach, Real cell,
                       const SphereSet& present, const Domain& domain) {
  const Vec3 box_lo = lo.array() - reach, box_hi = hi.array() + reach;
  std::vector<Vec3> kept;
  for (const Vec3& x : present.x)
    for_images(x, domain, [&](const Vec3& p) {
      if ((p.array() >= box_lo.array()).all() && (p.array() <= box_hi.array()).all())
        kept.push_back(p);
    });
  cell = std::max(cell, Real(1e-300));
  const Vec3 extent = (box_hi - box_lo).cwiseMax(Vec3::Constant(cell));
  // At most ~4 million cells (as OccupancyGrid): a sparse set over a large box gets larger cells.
  const Real max_cells = 4.0e6;
  const Real cells = (extent / cell).array().ceil().prod();
  if (cells > max_cells) cell *= std::cbrt(cells / max_cells) * 1.01;
  lo_ = box_lo;
  cell_ = cell;
  inv_cell_ = 1 / cell;
  for (int a = 0; a < 3; ++a)
    dims_[a] = std::max(1, static_cast<int>(std::ceil(extent[a] * inv_cell_)));
  // Counting sort by cell, stable: centres of a cell keep their order in `present`.
  const std::size_t n_cells = static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2];
  std::vector<int> cell_of(kept.size());
  start_.assign(n_cells + 1, 0);
  for (std::size_t k = 0; k < kept.size(); ++k) {
    int c[3];
    cell_index(kept[k], c);
    cell_of[k] = c[0] + dims_[0] * (c[1] + dims_[1] * c[2]);
    ++start_[cell_of[k] + 1];
  }
  for (std::size_t c = 0; c < n_cells; ++c) start_[c + 1] += start_[c];
  std::vector<int> fill(start_.begin(), start_.end() - 1);
  x_.resize(kept.size());
  for (std::size_t k = 0; k < kept.size(); ++k) x_[fill[cell_of[k]]++] = kept[k];
}

void CentreGrid::cell_index(const Vec3& x, int c[3]) const {
  for (int a = 0; a < 3; ++a) {
    const Real f = std::floor((x[a] - lo_[a]) * inv_cell_);
    c[a] = static_cast<int>(std::clamp<Real>(f, 0, dims_[a] - 1));
  }
}

bool CentreGrid::nearest(const Vec3& x, Real reach, Vec3& centre) const {
  int c[3];
  cell_index(x, c);
  Real best = reach * reach;
  bool found = false;
  const auto visit = [&](int i, int j, int k) {
    const int cell = i + dims_[0] * (j + dims_[1] * k);
    for (int p = start_[cell]; p < start_[cell + 1]; ++p) {
      const Real d2 = (x_[p] - x).squaredNorm();
      if (d2 < best) {
        best = d2;
        centre = x_[p];
        found = true;
      }
    }
  };
  // Ring n: the cells n steps from x's cell (Chebyshev). Every point of ring n is at least
  // (n - 1) cells from x, also for x or centres clamped into the border cells (clamping only
  // shortens index differences).
  const int last = static_cast<int>(std::ceil(reach * inv_cell_)) + 1;
  for (int n = 0; n <= last; ++n) {
    const Real inner = (n - 1) * cell_;
    if (n > 1 && inner * inner >= best) break;
    for (int dz = -n; dz <= n; ++dz) {
      const int k = c[2] + dz;
      if (k < 0 || k >= dims_[2]) continue;
      for (int dy = -n; dy <= n; ++dy) {
        const int j = c[1] + dy;
        if (j < 0 || j >= dims_[1]) continue;
        const bool face = std::abs(dz) == n || std::abs(dy) == n;
        for (int dx = -n; dx <= n; dx += face || n == 0 ? 1 : 2 * n) {
          const int i = c[0] + dx;
          if (i >= 0 && i < dims_[0]) visit(i, j, k);
        }
      }
    }
  }
  return found;
}

}  // namespace grainscale
