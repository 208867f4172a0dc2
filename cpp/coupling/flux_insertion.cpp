// Flux insertion into a level through its placement primitive.
#include "coupling/flux_insertion.hpp"

#include <algorithm>
#include <cmath>

namespace grainscale {

std::int64_t insert_flux(Level& level, const Level& parent, std::vector<FluxInserter>& inserters) {
  // One occupancy grid over every shell with particles waiting (the same on every rank).
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  Real max_new = 0;
  for (const FluxInserter& f : inserters) {
    if (!f.waiting()) continue;
    Vec3 a, b;
    f.placing_region().bounds(a, b);
    lo = lo.cwiseMin(a);
    hi = hi.cwiseMax(b);
    max_new = std::max(max_new, f.max_radius());
  }
  if (!(max_new > 0)) return 0;
  InsertionSite site = level.insertion_site(lo, hi, max_new);
  // The parent's grains within a face's size (the shells' width) of the shells.
  Real reach = 0;
  for (const FluxInserter& f : inserters) reach = std::max(reach, f.face_size());
  const CentreGrid material = parent.centres_near(lo, hi, reach);
  const WallClearance sight_walls(level.wall_set().walls(), lo, hi, reach);
  const MaterialSight sight{material, sight_walls, reach};
  std::int64_t placed = 0;
  std::vector<Vec3> x;
  std::vector<Real> r;
  for (FluxInserter& f : inserters) {
    if (!f.waiting()) continue;
    x.clear();
    r.clear();
    f.place(site.grid, site.walls, level.domain(), sight, x, r);
    if (r.empty()) continue;
    level.place_particles(x, r, f.velocity(), &f.spin(), f.material());
    placed += static_cast<std::int64_t>(r.size());
  }
  return placed;
}

}  // namespace grainscale
