// Velocity Verlet for translation and rotation (DESIGN.md 2.2):
//   v += dt/2 f/m, w += dt/2 tau/I, x += dt v  |  forces  |  v += dt/2 f/m, w += dt/2 tau/I
//
// Inside a run the closing half kick of one step and the opening half kick and drift of the next
// are one pass over the particles (kClosingKick): the same floating-point operations in the same
// order as two separate passes, so results do not depend on how a run is chunked, with half the
// memory traffic. The same pass resets the forces (f = m g, tau = 0) once they are used.
//
// kPlanar selects the 2-D disc mode (DESIGN.md 2.2): only x, y, v_x, v_y and w_z evolve; z never
// changes and v_z, w_x, w_y are held at exactly zero, so out-of-plane forces and in-plane torque
// components (which vanish for in-plane contacts anyway) are ignored.
#pragma once

#include <cstdint>
#include <vector>

#include "state/particle_store.hpp"

namespace grainscale {

// Opening half kick and drift of the owned particles, preceded by the previous step's closing
// half kick when kClosingKick; afterwards f = m g and tau = 0 (the start of the next force
// evaluation). Returns the largest squared displacement from `reference` (positions at the last
// neighbour-list build).
template <bool kPlanar, bool kClosingKick>
Real kick_drift(ParticleStore& ps, Real dt, const Vec3& gravity,
                const std::vector<Vec3>& reference);

// The same pass in two parts, for a force evaluation whose ghost forces are still travelling
// (GhostExchange::reverse_begin): first every owned particle with skip[i] == 0, then, once
// the forces are complete, those in `only`. Per particle the same operations as kick_drift.
template <bool kPlanar>
Real kick_drift_except(ParticleStore& ps, Real dt, const Vec3& gravity,
                       const std::vector<Vec3>& reference, const std::vector<std::uint8_t>& skip);
template <bool kPlanar>
Real kick_drift_only(ParticleStore& ps, Real dt, const Vec3& gravity,
                     const std::vector<Vec3>& reference, const std::vector<Index>& only);

// The larger of two displacements from kick_drift, NaN winning.
inline Real max_displacement(Real a, Real b) { return (b > a || b != b) && a == a ? b : a; }

// Closing half kick (the last step of a run).
template <bool kPlanar>
void kick(ParticleStore& ps, Real dt);

}  // namespace grainscale
