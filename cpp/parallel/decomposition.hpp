// Decomposition: how one level's box is split over its ranks (DESIGN.md 5).
//
// A processor grid P = (px, py, pz), px py pz = ranks, chosen to minimise the surface of a
// subdomain (hence the halo) for the box's shape, and per-axis cut positions: uniform at first,
// moved by load balancing so that the slabs along each axis hold equal numbers of particles (the
// tensor-product balancing of LAMMPS' `balance shift`). Rank r has grid coordinates
// (r mod px, (r / px) mod py, r / (px py)) and owns the particles whose (wrapped) centre lies in
// [cut_a[c_a], cut_a[c_a + 1]) on every axis a; the last slab also owns the upper face.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/types.hpp"
#include "state/domain.hpp"

namespace grainscale {

struct Decomposition {
  std::array<int, 3> grid{1, 1, 1};
  std::array<int, 3> coords{0, 0, 0};
  std::array<std::vector<Real>, 3> cuts;  // grid[a] + 1 positions per axis, domain lo ... hi
  int rank = 0;

  // Uniform cuts of `domain` over `grid` for `rank`.
  static Decomposition uniform(const Domain& domain, const std::array<int, 3>& grid, int rank);
  int ranks() const { return grid[0] * grid[1] * grid[2]; }
  int rank_at(const std::array<int, 3>& c) const {
    return c[0] + grid[0] * (c[1] + grid[1] * c[2]);
  }
  // Slab index along axis a of coordinate x (clamped into the grid).
  int slab(int axis, Real x) const;
  // Rank owning centre x; on periodic axes x is wrapped into the box first.
  int owner(const Vec3& x, const Domain& domain) const;
  Real lo(int axis) const { return cuts[axis][coords[axis]]; }
  Real hi(int axis) const { return cuts[axis][coords[axis] + 1]; }
  // Rank across the lower (dir = -1) or upper (dir = +1) face along `axis`; -1 at a closed end.
  int neighbor(int axis, int dir, const Domain& domain) const;
  // Narrowest slab along the split axes (infinity when nothing is split).
  Real narrowest_slab() const;
};

// The grid of `ranks` ranks with the smallest subdomain surface for a box of these edge lengths;
// pz = 1 in the 2-D mode. Among equal surfaces a split along z is preferred.
std::array<int, 3> choose_processor_grid(const Vec3& length, int ranks, int dimension);

// Cut positions lo = c_0 < ... < c_n = hi putting equal shares of the histogram `weights` (bins
// of equal width over [lo, hi]) in each of n slabs, each at least `min_width` wide (as close as
// possible to the equal shares when that constraint binds). Uniform cuts for an empty histogram.
std::vector<Real> balanced_cuts(const std::vector<Real>& weights, Real lo, Real hi, int n,
                                Real min_width);

}  // namespace grainscale
