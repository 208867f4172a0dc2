// Packing: random non-overlapping placement of particles inside a region (random sequential
// addition, largest first), avoiding the particles already present and the walls (a sphere may
// not touch any wall). A target is a particle count
// or a volume fraction of the region; if some particle finds no free spot after a bounded number
// of attempts the whole packing fails with an error saying how far it got (nothing is inserted
// and nothing is silently dropped).
//
// Random sequential addition jams at a volume fraction of about 0.38 for equal spheres (higher
// for wide size distributions); denser beds are made by letting a looser packing settle.
#pragma once

#include <cstdint>
#include <vector>

#include "core/types.hpp"
#include "insert/occupancy_grid.hpp"
#include "insert/region.hpp"
#include "insert/size_distribution.hpp"
#include "insert/wall_clearance.hpp"

namespace grainscale {

struct PackSpec {
  Region region = Region::box(Vec3::Zero(), Vec3::Ones());
  SizeDistribution radius = SizeDistribution::monodisperse(1);
  std::int64_t count = -1;    // number of particles, or -1 when volume_fraction is given
  Real volume_fraction = -1;  // particle volume / region volume, or -1 when count is given
  std::int32_t material = 0;  // material index of the level
  Vec3 velocity = Vec3::Zero();
  std::uint64_t seed = 0;
  int max_attempts = 1000;  // directed trials per particle once the region is nearly full
  // 2-D mode: centres in the plane z = plane_z, discs (volume_fraction is an area fraction of
  // the region's x-y cross-section); the region must then be an axis-aligned box.
  bool planar = false;
  Real plane_z = 0;
};

struct Placement {
  std::vector<Vec3> position;
  std::vector<Real> radius;
};

// Radii of a packing: `count` samples, or samples until their volume is closest to
// volume_fraction x region volume; returned sorted from largest to smallest.
std::vector<Real> pack_radii(const PackSpec& spec, Rng& rng);

// Places the radii (in order) in spec.region, avoiding the spheres already in `grid` (placed
// ones are added to it) and the walls. Throws std::runtime_error when a particle cannot be placed.
Placement place_in_region(const PackSpec& spec, const std::vector<Real>& radii, OccupancyGrid& grid,
                          const WallClearance& walls, Rng& rng);

}  // namespace grainscale
