// OccupancyGrid: the spheres already present around an insertion region, binned in a dense cell
// hash, to test a candidate sphere for overlaps in O(1). Cells are at least as large as the
// largest pair distance r_i + r_j that can occur, so the 27-cell stencil is complete; spheres
// outside the covered box are clamped into its border cells, which keeps the stencil complete.
#pragma once

#include <vector>

#include "core/types.hpp"
#include "state/domain.hpp"
#include "state/particle_store.hpp"

namespace grainscale {

// Spheres (centres, radii) already present near an insertion region.
struct SphereSet {
  std::vector<Vec3> x;
  std::vector<Real> r;
};

class OccupancyGrid {
 public:
  // Covers [lo, hi]; `max_new_radius` is the largest radius that will be tested or added and
  // `r_old` the largest radius of the spheres present (over all ranks). The spheres of `present`
  // (and, on periodic axes, their images) that can touch the box are added at once.
  OccupancyGrid(const Vec3& lo, const Vec3& hi, Real max_new_radius, Real r_old,
                const SphereSet& present, const Domain& domain);

  // The owned particles of `ps` that (or whose periodic images) can touch [lo, hi] grown by
  // max_new_radius + r_old, appended to `out`: what a rank contributes to the grid of an
  // insertion region (the level gathers them from every rank).
  static void collect_nearby(const Vec3& lo, const Vec3& hi, Real max_new_radius, Real r_old,
                             const ParticleStore& ps, const Domain& domain, SphereSet& out);

  void add(const Vec3& x, Real r);
  // Whether the sphere (x, r) overlaps a stored sphere (touching is allowed).
  bool overlaps(const Vec3& x, Real r) const;
  // Whether every centre in the box [lo, hi] (edges at most the cell size) would make a sphere
  // of radius r overlap one single stored sphere: no sphere of radius >= r fits there any more.
  bool covers(const Vec3& lo, const Vec3& hi, Real r) const;
  std::size_t size() const { return x_.size(); }

 private:
  int cell_of(const Vec3& x) const;
  Vec3 lo_ = Vec3::Zero();
  Real inv_cell_ = 1;
  int dims_[3] = {1, 1, 1};
  std::vector<int> head_, next_;
  std::vector<Vec3> x_;
  std::vector<Real> r_;
};

}  // namespace grainscale
