// Migration: owned particles whose centre has moved into another rank's subdomain go to that
// rank at a list rebuild, together with their contact histories (DESIGN.md 2.3, 5).
//
// Histories are carried (neighbor/contact_history.hpp) keyed by the partner's global id, or the
// wall primitive, at the particle that stores the pair: it travels with that particle and is
// found again when the receiver rebuilds its lists. Destinations come from the cut positions, so
// one personalised exchange also handles particles that move several ranks at once (after load
// balancing changed the cuts, or at a restart on a different decomposition).
#pragma once

#include <vector>

#include "neighbor/contact_history.hpp"
#include "parallel/communicator.hpp"
#include "parallel/decomposition.hpp"
#include "state/domain.hpp"
#include "state/particle_store.hpp"

namespace grainscale {

struct MigrationCounts {
  Index sent = 0;
  Index received = 0;
};

// Requires: no ghosts; positions wrapped on periodic axes; `origin[i]` the row of particle i in
// both carries (or -1). Afterwards the carries are rebuilt for the new owned set with origin[i] =
// i: kept particles first in their order, then the arrivals in rank order.
MigrationCounts migrate(ParticleStore& ps, std::vector<Index>& origin, HistoryCarry& pair_carry,
                        HistoryCarry& wall_carry, const Domain& domain,
                        const Decomposition& decomposition, const Communicator& comm);

}  // namespace grainscale
