// What a level's particles carry across the interface of a finer level's region during an
// exchange interval (DESIGN.md 4), per interface face, and what happens to its particles inside
// the region (its "shadow" of the finer level's material).
//
// start() remembers every particle inside or near the region cells (those within `margin` of the
// grid, gathered from every rank, so a particle that migrates during the interval is still
// known), with its position, mass and whether it was inside. finish() compares with now:
//   inward    outside then, inside now: booked on the face its straight path entered through
//             (ExchangeGrid::entry_face); a particle born inside during the interval (a stream of
//             this level pouring into the region) is booked on the face nearest to it
//   outward   inside then, outside now: booked on the face its path left through
//   vanished  inside then, gone now: the shadow's own removals (by an outlet, or lost through a
//             closed side of the box when its id is in the level's lost log), which the
//             hierarchy sets against the finer level's discharge
// Every particle is classified by where it was at start(), so the books of the levels add up
// exactly whatever happens during the interval. The interval is short: a particle moves far less
// than a cell, and one that enters and leaves again within it is not seen.
#pragma once

#include <unordered_map>
#include <vector>

#include "field/exchange_grid.hpp"
#include "parallel/communicator.hpp"
#include "state/domain.hpp"
#include "state/particle_store.hpp"

namespace grainscale {

struct FaceFlux {
  Real mass = 0;   // kg
  Real count = 0;  // particles
  // kg m/s: momentum / mass is the crossings' mean velocity, weighted by speed and so ahead of
  // the bulk; a measurement only (what the child places moves with the bulk, Interface::book)
  Vec3 momentum = Vec3::Zero();
  Vec3 spin = Vec3::Zero();  // sum of I w (kg m^2/s): the face's spin is spin / inertia
  Real inertia = 0;          // sum of I (kg m^2)
};

struct IntervalFlux {
  std::vector<FaceFlux> inward, outward;  // per interface face
  Real vanished_mass = 0;                 // kg: inside at start, removed since
  Real vanished_count = 0;
  Real vanished_lost_mass = 0;  // kg: the part of vanished_mass lost through closed sides
  Real inside_mass = 0;         // kg: the level's particles in the region cells at finish
};

class FaceFluxMeter {
 public:
  // Collective.
  void start(const ParticleStore& ps, const ExchangeGrid& grid, const Domain& domain, Real margin,
             const Communicator& comm);
  // Collective: summed over the ranks (identical on every rank); `lost`: this rank's ids lost
  // since start().
  IntervalFlux finish(const ParticleStore& ps, const ExchangeGrid& grid, const Domain& domain,
                      const std::vector<GlobalId>& lost, const Communicator& comm);

 private:
  struct Start {
    GlobalId id;
    Vec3 x;
    Real mass;
    bool inside;
  };
  std::vector<Start> start_;
  std::unordered_map<GlobalId, std::size_t> index_;  // id -> start_ entry
};

}  // namespace grainscale
