// ExchangeGrid: the cells through which two levels of a hierarchy exchange averaged data
// (DESIGN.md 4), made from a region without hand work: hexahedral cells tile the region's
// bounding box (edges as close to `cell_size` as an integer number of cells allows, so a box
// region is tiled exactly); a cell belongs to the region when its centre does. The fine level
// lives in the union of the region's cells.
//
//   boundary cells  region cells with a face neighbour outside the region (or outside the grid)
//   interface faces the faces between a region cell and a cell outside it, each with an id, the
//                   region cell, its axis and side, the unit normal into the region, centre and
//                   area; faces on a closed side of the simulation box are left out (no particle
//                   crosses them)
//   interior cells  region cells that are not boundary cells: where the finer level's flow is
//                   its own and drives the coarser level (fine -> coarse feedback). A grid
//                   without one is refused: its cells are too coarse for the region.
#pragma once

#include <vector>

#include "field/field_grid.hpp"
#include "insert/region.hpp"
#include "state/domain.hpp"

namespace grainscale {

struct InterfaceFace {
  int cell = 0;                // the region cell the face bounds
  int axis = 0;                // 0, 1, 2
  int side = -1;               // -1: the cell's lower face along `axis`, +1: its upper face
  Vec3 normal = Vec3::Zero();  // unit, into the region
  Vec3 centre = Vec3::Zero();
  Real area = 0;
};

class ExchangeGrid {
 public:
  // Throws InvalidArgument (naming `what`) for a non-positive cell size or a region with no
  // cell, or no interior cell.
  ExchangeGrid(const Region& region, Real cell_size, const Domain& domain, const std::string& what);

  const FieldGrid& grid() const { return grid_; }
  bool inside(int cell) const { return cell >= 0 && inside_[cell]; }
  bool boundary(int cell) const { return cell >= 0 && boundary_[cell]; }
  // Whether the point lies in a region cell.
  bool contains(const Vec3& x) const { return inside(grid_.cell_of(x)); }
  const std::vector<InterfaceFace>& faces() const { return faces_; }
  // The interface faces of a cell (indices into faces()).
  const std::vector<int>& faces_of(int cell) const { return faces_of_[cell]; }
  int region_cells() const { return region_cells_; }
  int interior_cells() const { return interior_cells_; }
  // Whether x lies in a region cell or within `band` of one (band < the smallest cell edge).
  bool near_region(const Vec3& x, Real band) const;
  // The interface face whose rectangle is nearest to x; -1 if there is no face.
  int nearest_face(const Vec3& x) const;
  // The face a straight move from `from` (outside the region cells) to `to` (inside) enters
  // through: the face between the last outside cell and the first region cell along the
  // segment; -1 when the segment never enters or enters through no interface face.
  int entry_face(const Vec3& from, const Vec3& to) const;

 private:
  FieldGrid grid_;
  std::vector<char> inside_, boundary_;
  std::vector<InterfaceFace> faces_;
  std::vector<std::vector<int>> faces_of_;
  int region_cells_ = 0, interior_cells_ = 0;
};

}  // namespace grainscale
