// Random sequential placement of waiting particles in a region (stream batches, the flux
// insertion of a hierarchy's fine level): first come, first served, each tried at up to
// `max_attempts` random centres of `region`, kept where it overlaps no sphere of `grid` and
// touches no wall (and, given a domain, whose centre lies inside it along its closed axes; given
// `sight`, where the material reaches: MaterialSight). A run of `give_up_after` consecutive
// failures means the region is full: the rest waits.
#pragma once

#include <istream>
#include <ostream>
#include <vector>

#include "insert/centre_grid.hpp"
#include "insert/occupancy_grid.hpp"
#include "insert/random.hpp"
#include "insert/region.hpp"
#include "insert/wall_clearance.hpp"
#include "state/domain.hpp"

namespace grainscale {

// Where another level's material reaches (a hierarchy's flux insertion): a centre is kept only
// if a centre of `material` lies within `reach` of it and no wall of `walls` lies across the
// segment to the nearest one. So no grain is placed where no grain of that material can be:
// under a floor, behind a wall, which the clearance test alone cannot tell from the bed's side.
struct MaterialSight {
  const CentreGrid& material;  // built for a reach of at least `reach`
  const WallClearance& walls;  // complete for segments up to `reach` long
  Real reach = 0;              // m
};

// Places radii of `pending` in order; placed ones are appended to position/radius, added to the
// grid and removed from `pending` (the others keep their order).
void place_pending(std::vector<Real>& pending, const Region& region, int max_attempts, Rng& rng,
                   OccupancyGrid& grid, const WallClearance& walls, std::vector<Vec3>& position,
                   std::vector<Real>& radius, const Domain* domain = nullptr,
                   const MaterialSight* sight = nullptr, int give_up_after = 32);

// The waiting radii and the placement engine in a checkpoint text (" n r_1 ... r_n <engine>",
// shared by the stream and the flux inserters); read_pending leaves `in` failed on bad text.
void write_pending(std::ostream& out, const std::vector<Real>& pending, const Rng& rng);
void read_pending(std::istream& in, std::vector<Real>& pending, Rng& rng);

}  // namespace grainscale
