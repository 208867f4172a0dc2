// CellGrid: linked-cell binning of points into boxes whose edges are at least `min_cell` long,
// covering the points' bounding box. Every pair closer than a cut-off lies within reach(cutoff)
// cells of each other along each axis, for any cell size and any size ratio: wide size ratios
// cost more candidates, not correctness. Pair lists use cells of the cut-off (27-cell stencil)
// unless the radii differ by a factor 2 or more: then cells of half the cut-off (5 x 5 x 5
// stencil, 15.6 instead of 27 cut-off cubes of candidates). Measured list builds with half cells
// (bench/cpp/bench_neighbor_build): 4-10 % slower for equal spheres, 11-18 % faster at 1:3.
#pragma once

#include <array>
#include <vector>

#include "core/types.hpp"

namespace grainscale {

class CellGrid {
 public:
  // Bins points x[0, n). The grid never has more than max(max_cells, 1) cells: sparse systems
  // get larger cells instead of a huge empty grid.
  void build(const Vec3* x, Index n, Real min_cell, std::size_t max_cells);
  // The binning for pair searches with this cut-off, given the ratio of the largest to the
  // smallest radius: cells of the cut-off (at most 2 n + 64 of them) or, for size ratios of 2
  // and more, of half the cut-off (at most 16 n + 64). Sparse systems get larger cells.
  void build_for_pairs(const Vec3* x, Index n, Real cutoff, Real size_ratio) {
    const bool wide = size_ratio >= 2;
    build(x, n, wide ? 0.5 * cutoff : cutoff, (wide ? 16 : 2) * static_cast<std::size_t>(n) + 64);
  }
  // Cells to search on each side along each axis for pairs closer than `cutoff`.
  std::array<int, 3> reach(Real cutoff) const;
  // After the points were reordered to `particles` (point k is now the old particles[k]), makes
  // the grid describe the new order: same cells, particles = 0, 1, ..., n - 1.
  void renumber_sorted();

  std::array<int, 3> dims{1, 1, 1};
  std::vector<Index> cell_start;  // n_cells + 1 offsets into `particles`
  std::vector<Index> particles;   // point indices grouped by cell, ascending within a cell
  std::vector<int> cell_of;       // cell of each point

  int n_cells() const { return dims[0] * dims[1] * dims[2]; }
  std::array<int, 3> coords(int cell) const {
    return {cell % dims[0], (cell / dims[0]) % dims[1], cell / (dims[0] * dims[1])};
  }
  int cell_id(int cx, int cy, int cz) const { return cx + dims[0] * (cy + dims[1] * cz); }

 private:
  std::vector<Index> fill_;  // build scratch
  Vec3 origin_ = Vec3::Zero();
  Vec3 inv_edge_ = Vec3::Ones();
};

}  // namespace grainscale
