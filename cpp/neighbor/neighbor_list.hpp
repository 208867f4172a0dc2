// Verlet neighbour lists with per-entry contact history.
//
// PairList: a half list in CSR form over owned particles. A pair is stored once, at the
// particle with the smaller global id (owned or ghost partner alike), so a pair's orientation
// and owner never depend on the local ordering: histories survive sorting, rebuilds and, under
// MPI, migration. The list holds pairs with |x_i - x_j| < r_i + r_j + skin at build time and
// stays valid until some particle has moved more than skin/2 (plus wall motion for walls).
// Wall list: per owned particle, the wall primitives (walls, mesh triangles) within r_i + skin.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "core/page_vector.hpp"
#include "core/types.hpp"
#include "geometry/wall.hpp"
#include "neighbor/cell_grid.hpp"
#include "state/particle_store.hpp"

namespace grainscale {

struct ContactList {
  PageVector<Index> first;    // n_owned + 1
  PageVector<Index> partner;  // local particle index, or wall index
  PageVector<Real> history;   // history_stride values per entry
  // 1 while the entry touches (its history may be non-zero). Lets the force loop skip the
  // history of the many non-touching entries instead of clearing it every step.
  PageVector<std::uint8_t> touching;
  int history_stride = 0;
  // Build scratch kept between rebuilds (fresh large buffers cost page faults each time).
  PageVector<std::pair<Index, Index>> scratch_pairs;
  PageVector<Index> scratch_count;
  // The owned particles that have entries, ascending (index_rows). The wall loop walks only
  // these: near walls they are a thin, scattered subset.
  PageVector<Index> rows;
  // The row (owned particle) of every entry (index_rows): the pair loop reads it in order
  // instead of working it out from `first` for every chunk.
  PageVector<Index> owner;

  std::size_t size() const { return partner.size(); }
};

// Fills list.rows and list.owner from list.first: after a build and after a list is loaded.
void index_rows(ContactList& list);

// Builds the particle half list from a grid binned over all local (owned + ghost) particles.
// cutoff: the largest pair cut-off, 2 r_max + skin over the local particles (sets the stencil).
void build_pair_list(const ParticleStore& ps, const CellGrid& grid, Real cutoff, Real skin,
                     ContactList& list);

// Builds the particle-wall list. Entries are wall primitives: primitive_first[w] + t for
// triangle t of a mesh wall w, primitive_first[w] for any other wall; per particle they come in
// increasing primitive order, so the triangles of one mesh are contiguous.
void build_wall_list(const ParticleStore& ps, const std::vector<Wall>& walls,
                     const std::vector<Index>& primitive_first, Real skin, ContactList& list);

}  // namespace grainscale
