// Velocity Verlet for translation and rotation of spheres (DESIGN.md 2.2):
//   v += dt/2 f/m, w += dt/2 tau/I, x += dt v  |  forces  |  v += dt/2 f/m, w += dt/2 tau/I
#pragma once

#include "state/particle_store.hpp"

namespace grainscale {

// First half kick and drift of the owned particles. Returns the largest squared displacement
// from `reference` (positions at the last neighbour-list build).
Real kick_drift(ParticleStore& ps, Real dt, const std::vector<Vec3>& reference);

// Second half kick.
void kick(ParticleStore& ps, Real dt);

}  // namespace grainscale
