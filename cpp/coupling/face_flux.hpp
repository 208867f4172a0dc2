// Coarse -> fine, particles entering (DESIGN.md 4): what a level's particles carry into the
// region cells of a finer level's ExchangeGrid during an exchange interval, per interface face.
//
// start() remembers where the particles near the region are (those within `margin` of the grid,
// gathered from every rank, so a particle that migrates during the interval is still known);
// finish() takes every particle that was outside the region cells then and is inside now and
// books it on the face its straight path entered through (ExchangeGrid::entry_face; the
// interval is short, a particle moves far less than a cell). A particle that enters and leaves
// again within one interval is not seen; one that ends an interval in the region was booked
// once, when it entered.
#pragma once

#include <unordered_map>
#include <vector>

#include "coupling/exchange_grid.hpp"
#include "parallel/communicator.hpp"
#include "state/domain.hpp"
#include "state/particle_store.hpp"

namespace grainscale {

struct FaceFlux {
  Real mass = 0;                 // kg
  Real count = 0;                // particles
  Vec3 momentum = Vec3::Zero();  // kg m/s: the face's velocity is momentum / mass
  Vec3 spin = Vec3::Zero();      // sum of I w (kg m^2/s): the face's spin is spin / inertia
  Real inertia = 0;              // sum of I (kg m^2)
};

class FaceFluxMeter {
 public:
  // Collective.
  void start(const ParticleStore& ps, const ExchangeGrid& grid, const Domain& domain, Real margin,
             const Communicator& comm);
  // Collective: per face of `grid`, summed over the ranks (identical on every rank).
  std::vector<FaceFlux> finish(const ParticleStore& ps, const ExchangeGrid& grid,
                               const Domain& domain, const Communicator& comm);

 private:
  std::unordered_map<GlobalId, Vec3> start_;  // outside the region cells at start()
};

}  // namespace grainscale
