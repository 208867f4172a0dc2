// Flux insertion: the child level of an interface places what its FluxInserters owe, through
// the level's placement primitive (Level::insertion_site, Level::place_particles).
#pragma once

#include <cstdint>
#include <vector>

#include "coupling/flux_inserter.hpp"
#include "level/level.hpp"

namespace grainscale {

// Collective: places what the inserters owe (each its scheduled particles, in order; every rank
// the same particles, each keeps its own) with their velocity and spin, in one occupancy grid
// over every shell with particles waiting, where the material of `parent` (the level whose
// crossings the inserters booked; collective over its ranks as well) reaches: within a face's
// size of a parent grain, no wall between them (MaterialSight); returns the number placed.
std::int64_t insert_flux(Level& level, const Level& parent, std::vector<FluxInserter>& inserters);

}  // namespace grainscale
