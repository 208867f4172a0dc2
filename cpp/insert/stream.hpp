// Stream insertion: particles enter through a face (rectangle or disc) at a mass rate with an
// initial velocity. Batches are due at t_k = start + k * every; batch k samples (from the size
// distribution, seeded) the particles for the mass of the interval [t_k, t_k+1) (clipped at
// `stop`) and places them at random without overlaps, and without touching a wall, in a slab on
// the downstream side of the face. Particles that find no free spot stay pending and are tried
// again at the next batch time (also after `stop`, until none is left): nothing is dropped.
//
// Bookkeeping (s, kg): requested = rate x (min(t, stop) - start)^+ (continuous);
// scheduled = mass of all sampled particles = inserted + pending. After batch k the scheduled mass
// is the mass due up to t_k+1, so inserted + pending leads the requested mass by at most one
// batch (plus one particle).
//
// Defaults: every = largest diameter / (normal insertion speed) (the time for a particle to travel
// one diameter); slab thickness = max(2 largest diameters, normal speed x every), so a batch is
// spread over the distance the previous one travelled.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "insert/occupancy_grid.hpp"
#include "insert/region.hpp"
#include "insert/size_distribution.hpp"
#include "insert/wall_clearance.hpp"

namespace grainscale {

struct StreamSpec {
  Face face = Face::disc(Vec3::Zero(), Vec3::UnitZ(), 1);
  SizeDistribution radius = SizeDistribution::monodisperse(1);
  Real mass_rate = 0;  // kg/s
  std::int32_t material = 0;
  Vec3 velocity = Vec3::Zero();  // m/s
  std::uint64_t seed = 0;
  Real start = 0;         // s
  Real stop = INFINITY;   // s
  Real every = 0;         // s between batches; 0 picks the default
  int max_attempts = 50;  // trial positions per pending particle and batch
};

class StreamInserter {
 public:
  // density: of the material (kg/m^3), for the masses.
  StreamInserter(const StreamSpec& spec, Real density);

  const StreamSpec& spec() const { return spec_; }
  Real interval() const { return every_; }
  Real thickness() const { return thickness_; }
  const Region& slab() const { return slab_; }
  // Unit vector from the face into the slab (the side the velocity points to).
  const Vec3& direction() const { return direction_; }
  // Mass (kg) of a particle of radius r; the same expression as Level::add_particles.
  Real mass_of(Real r) const { return density_ * (4.0 / 3.0) * M_PI * r * r * r; }

  // Samples the particles of every batch due at `time` (within `tolerance`) into the pending
  // list; returns true when a placement pass is due now.
  bool schedule(Real time, Real tolerance);
  // Places pending particles (first come, first served) without overlaps with `grid` and clear
  // of `walls`; placed ones are appended to position/radius and added to the grid. Stops early
  // after a run of failures (the slab is full).
  void place(OccupancyGrid& grid, const WallClearance& walls, std::vector<Vec3>& position,
             std::vector<Real>& radius);

  Real requested_mass(Real time) const;
  Real scheduled_mass() const { return scheduled_mass_; }
  Real inserted_mass() const { return inserted_mass_; }
  Real pending_mass() const;
  std::int64_t inserted_count() const { return inserted_count_; }
  std::int64_t pending_count() const { return static_cast<std::int64_t>(pending_.size()); }
  std::int64_t batches() const { return next_batch_; }
  const std::vector<Real>& pending_radii() const { return pending_; }

  // Complete mutable state (start time, counters, pending particles, random engine) as text, and
  // back; the rest of the spec is not part of it (re-create the stream, then load).
  std::string save_state() const;
  void load_state(const std::string& state);

 private:
  StreamSpec spec_;
  Real density_ = 0;
  Real every_ = 0, thickness_ = 0;
  Vec3 direction_ = Vec3::UnitZ();
  Region slab_ = Region::box(Vec3::Zero(), Vec3::Ones());
  Rng rng_;
  std::int64_t next_batch_ = 0;
  Real scheduled_mass_ = 0, inserted_mass_ = 0;
  std::int64_t inserted_count_ = 0;
  std::vector<Real> pending_;  // radii waiting for a free spot, in sampling order
};

}  // namespace grainscale
