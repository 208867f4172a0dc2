// Velocity Verlet for translation and rotation (DESIGN.md 2.2):
//   v += dt/2 f/m, w += dt/2 tau/I, x += dt v  |  forces  |  v += dt/2 f/m, w += dt/2 tau/I
//
// Inside a run the closing half kick of one step and the opening half kick and drift of the next
// are one pass over the particles (kClosingKick): the same floating-point operations in the same
// order as two separate passes, so results do not depend on how a run is chunked, with half the
// memory traffic. The same pass resets the forces (f = m g, tau = 0) once they are used. In 3-D
// it takes kPackLanes particles at a time (kick_drift_lanes.hpp), with the same bits.
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
// evaluation). Returns the largest squared drift velocity |v|^2 (NaN if any is NaN): dt times
// its root bounds every particle's move in this step, which spares the pass reading the positions
// at the last neighbour-list build (max_displacement2) on most steps.
template <bool kPlanar, bool kClosingKick>
Real kick_drift(ParticleStore& ps, Real dt, const Vec3& gravity);

// The same pass in two parts, for a force evaluation whose ghost forces are still travelling
// (GhostExchange::reverse_begin): first every owned particle with skip[i] == 0, then, once
// the forces are complete, those in `only`. Per particle the same operations as kick_drift.
template <bool kPlanar>
Real kick_drift_except(ParticleStore& ps, Real dt, const Vec3& gravity,
                       const std::vector<std::uint8_t>& skip);
template <bool kPlanar>
Real kick_drift_only(ParticleStore& ps, Real dt, const Vec3& gravity,
                     const std::vector<Index>& only);

// The larger of two results of kick_drift (or of max_displacement2), NaN winning.
inline Real larger_or_nan(Real a, Real b) { return (b > a || b != b) && a == a ? b : a; }

// The largest squared displacement of an owned particle from `reference` (NaN if any is NaN).
Real max_displacement2(const ParticleStore& ps, const std::vector<Vec3>& reference);

// Closing half kick (the last step of a run).
template <bool kPlanar>
void kick(ParticleStore& ps, Real dt);

}  // namespace grainscale
