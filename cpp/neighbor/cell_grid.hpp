// CellGrid: linked-cell binning of points into boxes whose edges are at least `min_cell` long,
// covering the points' bounding box. With min_cell >= the largest pair cut-off (largest
// diameter + skin) the 27-cell stencil finds every pair, for any size ratio; wide size ratios
// cost more pairs per cell, not correctness.
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
