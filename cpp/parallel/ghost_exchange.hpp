// GhostExchange: creates ghost particles and moves data between owners and ghosts.
// Serial build: ghosts are periodic images. The MPI build (later) adds halo copies from
// neighbouring ranks through the same three operations.
//   build   – after owned particles were wrapped into the box: one image per periodic
//             direction combination for every owned particle within `cutoff` of a face;
//   forward – copies positions (owner + shift) and velocities to ghosts every step;
//   reverse – adds ghost forces and torques onto their owners (each pair is computed once).
#pragma once

#include "state/domain.hpp"
#include "state/particle_store.hpp"

namespace grainscale {

class GhostExchange {
 public:
  void build(ParticleStore& ps, const Domain& domain, Real cutoff) const;
  void forward(ParticleStore& ps) const { ps.update_ghosts(); }
  void reverse(ParticleStore& ps) const;
};

// Wraps owned particles into the box along periodic axes.
void wrap_periodic(ParticleStore& ps, const Domain& domain);

}  // namespace grainscale
