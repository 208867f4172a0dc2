#include "parallel/decomposition.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace grainscale {

Decomposition Decomposition::uniform(const Domain& domain, const std::array<int, 3>& grid,
                                     int rank) {
  Decomposition d;
  d.grid = grid;
  d.rank = rank;
  d.coords = {rank % grid[0], (rank / grid[0]) % grid[1], rank / (grid[0] * grid[1])};
  for (int a = 0; a < 3; ++a) {
    const Real lo = domain.lo[a], hi = domain.hi[a];
    d.cuts[a].resize(grid[a] + 1);
    for (int k = 0; k <= grid[a]; ++k) d.cuts[a][k] = lo + (hi - lo) * k / grid[a];
    d.cuts[a].front() = lo;  // exact ends, whatever the rounding of the interior cuts
    d.cuts[a].back() = hi;
  }
  return d;
}

int Decomposition::slab(int axis, Real x) const {
  const std::vector<Real>& c = cuts[axis];
  // Interior cuts c[1] .. c[n-1]; the slab is the number of them at or below x.
  const auto it = std::upper_bound(c.begin() + 1, c.end() - 1, x);
  return static_cast<int>(it - (c.begin() + 1));
}

int Decomposition::owner(const Vec3& x, const Domain& domain) const {
  std::array<int, 3> c;
  for (int a = 0; a < 3; ++a) {
    Real v = x[a];
    if (domain.periodic[a] && (v < domain.lo[a] || v >= domain.hi[a])) {
      const Real len = domain.hi[a] - domain.lo[a];
      v -= len * std::floor((v - domain.lo[a]) / len);
    }
    c[a] = grid[a] == 1 ? 0 : slab(a, v);
  }
  return rank_at(c);
}

int Decomposition::neighbor(int axis, int dir, const Domain& domain) const {
  std::array<int, 3> c = coords;
  c[axis] += dir;
  if (c[axis] < 0 || c[axis] >= grid[axis]) {
    if (!domain.periodic[axis]) return -1;
    c[axis] = (c[axis] + grid[axis]) % grid[axis];
  }
  return rank_at(c);
}

Real Decomposition::narrowest_slab() const {
  Real w = std::numeric_limits<Real>::infinity();
  for (int a = 0; a < 3; ++a)
    if (grid[a] > 1)
      for (int k = 0; k < grid[a]; ++k) w = std::min(w, cuts[a][k + 1] - cuts[a][k]);
  return w;
}

std::array<int, 3> choose_processor_grid(const Vec3& length, int ranks, int dimension) {
  std::array<int, 3> best{ranks, 1, 1};
  Real best_area = std::numeric_limits<Real>::infinity();
  // px ascending, then py ascending: among equal surfaces the split along z comes first.
  for (int px = 1; px <= ranks; ++px) {
    if (ranks % px) continue;
    for (int py = 1; py <= ranks / px; ++py) {
      if ((ranks / px) % py) continue;
      const int pz = ranks / px / py;
      if (dimension == 2 && pz != 1) continue;
      const Real a = length[0] / px, b = length[1] / py, c = length[2] / pz;
      // The halo grows with the subdomain's surface (its perimeter in 2-D).
      const Real area = dimension == 2 ? a + b : a * b + b * c + a * c;
      if (area < best_area * (1 - 1e-12)) {
        best = {px, py, pz};
        best_area = area;
      }
    }
  }
  return best;
}

std::vector<Real> balanced_cuts(const std::vector<Real>& counts, Real lo, Real hi, int n,
                                Real min_width) {
  std::vector<Real> cuts(n + 1);
  const std::size_t bins = counts.size();
  Real total = 0;
  for (Real c : counts) total += c;
  const Real bin = (hi - lo) / static_cast<Real>(std::max<std::size_t>(bins, 1));
  // Equal shares: cut k where the cumulative count reaches k total / n (linear within a bin).
  std::size_t b = 0;
  Real below = 0;  // weight in bins [0, b)
  for (int k = 0; k <= n; ++k) {
    if (!(total > 0) || k == 0 || k == n) {
      cuts[k] = lo + (hi - lo) * k / n;
      continue;
    }
    const Real target = total * k / n;
    while (b < bins && below + counts[b] < target) below += counts[b++];
    const Real inside = b < bins && counts[b] > 0 ? (target - below) / counts[b] : 0;
    cuts[k] = lo + (static_cast<Real>(b) + inside) * bin;
  }
  cuts.front() = lo;
  cuts.back() = hi;
  // Minimum width: push cuts up from below, then down from above (feasible when n w <= hi - lo).
  const Real w = std::min(min_width, (hi - lo) / n);
  for (int k = 1; k < n; ++k) cuts[k] = std::max(cuts[k], cuts[k - 1] + w);
  for (int k = n - 1; k >= 1; --k) cuts[k] = std::min(cuts[k], cuts[k + 1] - w);
  return cuts;
}

}  // namespace grainscale
