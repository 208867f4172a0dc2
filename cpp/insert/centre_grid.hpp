// CentreGrid: the centres of a set of spheres binned in cells about one sphere across, to find the
// centre nearest to a point within a reach of many cells (MaterialSight: where another level's
// material is). The search visits rings of cells outward from the point's cell and stops as soon
// as no ring farther out can hold a nearer centre, so in a bed it looks at a few dozen centres
// however long the reach; a grid with cells as large as the reach would scan thousands.
#pragma once

#include <vector>

#include "core/types.hpp"
#include "insert/occupancy_grid.hpp"
#include "state/domain.hpp"

namespace grainscale {

class CentreGrid {
 public:
  // Queries lie in [lo, hi] and look `reach` (m) far; the centres of `present` (and, on periodic
  // axes, their images) within reach of the box are kept, in cells about `cell` (m) across.
  CentreGrid(const Vec3& lo, const Vec3& hi, Real reach, Real cell, const SphereSet& present,
             const Domain& domain);

  // The stored centre nearest to x within `reach` (at most the reach the grid was built with);
  // false if there is none.
  bool nearest(const Vec3& x, Real reach, Vec3& centre) const;
  std::size_t size() const { return x_.size(); }

 private:
  void cell_index(const Vec3& x, int c[3]) const;
  Vec3 lo_ = Vec3::Zero();
  Real cell_ = 1, inv_cell_ = 1;
  int dims_[3] = {1, 1, 1};
  std::vector<int> start_;  // centres of cell c: x_[start_[c] .. start_[c + 1])
  std::vector<Vec3> x_;
};

}  // namespace grainscale
