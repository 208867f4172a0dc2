// ContactState: a level's contact lists (particle pairs, wall contacts) and the histories they
// carry across a list build, with each owned particle's row in those carries.
#pragma once

#include <vector>

#include "neighbor/contact_history.hpp"
#include "neighbor/neighbor_list.hpp"

namespace grainscale {

// The lists and carried histories of a level (the work estimate reads them; migration moves
// the carries with their particles).
struct ContactState {
  ContactList pairs, walls;
  HistoryCarry pair_carry, wall_carry;
  std::vector<Index> origin;  // per owned particle: index when histories were saved, or -1
};

}  // namespace grainscale
