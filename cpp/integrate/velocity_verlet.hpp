// Velocity Verlet for translation and rotation (DESIGN.md 2.2):
//   v += dt/2 f/m, w += dt/2 tau/I, x += dt v  |  forces  |  v += dt/2 f/m, w += dt/2 tau/I
// kPlanar selects the 2-D disc mode (DESIGN.md 2.2): only x, y, v_x, v_y and w_z evolve; z never
// changes and v_z, w_x, w_y are held at exactly zero, so out-of-plane forces and in-plane torque
// components (which vanish for in-plane contacts anyway) are ignored.
#pragma once

#include "state/particle_store.hpp"

namespace grainscale {

// First half kick and drift of the owned particles. Returns the largest squared displacement
// from `reference` (positions at the last neighbour-list build).
template <bool kPlanar>
Real kick_drift(ParticleStore& ps, Real dt, const std::vector<Vec3>& reference);

// Second half kick.
template <bool kPlanar>
void kick(ParticleStore& ps, Real dt);

}  // namespace grainscale
