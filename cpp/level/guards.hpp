// Guards: checks that stop a run before an unnoticed failure spoils it (issue 25).
//
//   - step displacement: a particle moving more than max_step_displacement x its radius in one
//     step (a particle or wall can be passed through unseen: tunnelling), or a non-finite
//     position or velocity. Checked every step from the largest squared speed the kick-drift
//     pass already returns (integrate/velocity_verlet.hpp): one compare against
//     (fraction x smallest radius / dt)^2; only when that bound is exceeded are the particles
//     scanned for the offender (GuardLimits' rare path, guards.cpp).
//   - overlap: a contact overlap above max_overlap x the smaller radius (x the radius for a
//     wall), from the contact statistics (ContactStats::max_overlap_ratio) of the last step of
//     each run() chunk.
//   - wall speed: a wall that can move more than max_step_displacement x the smallest radius in
//     one step (Wall::step_bound), checked when each run() chunk starts.
//
// A guard that trips throws std::runtime_error on every rank (Communicator::raise_if_any)
// naming the particle (global id), the step, the value against the limit and a remedy. Guards
// only read: runs they do not stop are bit-identical to runs without them.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "geometry/wall.hpp"
#include "neighbor/neighbor_list.hpp"
#include "state/particle_store.hpp"

namespace grainscale {

struct WallPrimitives;  // contact/wall_loop.hpp

struct GuardLimits {
  bool enabled = false;
  Real max_step_displacement = 0.5;  // fraction of the particle's radius moved in one step
  Real max_overlap = 0.5;            // fraction of the smaller radius of a contact
};

// The largest overlap ratio among this rank's list entries, and its contact.
struct OverlapFinding {
  Real ratio = 0;   // overlap / smaller radius (/ radius for a wall)
  GlobalId a = -1;  // particle
  GlobalId b = -1;  // other particle, or -1 - wall index
};

// Scans the owned particles (the rare path): the first non-finite position or velocity (fatal =
// true), else the particle that moved farthest in units of its radius in the last step (dt |v|)
// if above `fraction`. Returns the message without the remedy, empty if none.
std::string find_step_violation(const ParticleStore& ps, Real dt, Real fraction, std::int64_t step,
                                bool& fatal);

// Recomputes the overlaps of the pair and wall list entries at the current positions.
OverlapFinding largest_overlap(const ParticleStore& ps, const ContactList& pairs,
                               const ContactList& walls, const std::vector<Wall>& wall_list,
                               const WallPrimitives& primitives);

}  // namespace grainscale
