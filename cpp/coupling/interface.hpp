// Interface: the coupling between a level of a hierarchy (the parent) and the finer level
// embedded in a region of it (the child), DESIGN.md 4. It holds the ExchangeGrid of the region,
// the parent's face flux meter, the transfer ledger and inserter of every interface face, and a
// cell averager on each side; the hierarchy (python/grainscale/hierarchy.py) calls it once per
// exchange interval and computes the controllers from the averages. Every call that takes a
// Level is collective over that level's ranks.
//
// Mass is exchanged, never created: what the parent carries in across a face is owed to the
// child, what it carries out the child owes, and what leaves the child's region through a face is
// owed back to it (FluxInserter). The child pays by insertion or by extraction (its particles
// nearest the face removed). What the child discharges (outlets, closed sides) the parent's
// material in the region must give up as well: the hierarchy books that debt and pays what the
// parent's own outflow leaves unpaid with remove_shadow().
#pragma once

#include <memory>
#include <vector>

#include "coupling/face_flux.hpp"
#include "coupling/flux_inserter.hpp"
#include "field/cell_average.hpp"
#include "field/exchange_grid.hpp"
#include "level/level.hpp"

namespace grainscale {

struct InterfaceSpec {
  Region region = Region::box(Vec3::Zero(), Vec3::Ones());
  Real cell_size = 0;  // m
  SizeDistribution fine_radius = SizeDistribution::monodisperse(1);
  Real fine_density = 0;  // kg/m^3
  std::int32_t fine_material = 0;
  Real size_ratio = 1;  // parent / child particle size (h_parent / h_child)
  Real deadband = 0;    // kg, of the faces' ledgers: the largest parent particle's mass
  std::uint64_t seed = 0;
};

class Interface {
 public:
  // parent_domain: the box of the parent level (faces on its closed sides are no interface).
  Interface(const InterfaceSpec& spec, const Domain& parent_domain, int dimension);

  const ExchangeGrid& grid() const { return *grid_; }
  std::shared_ptr<const ExchangeGrid> shared_grid() const { return grid_; }
  const InterfaceSpec& spec() const { return spec_; }

  // Parent: the start and the end of an interval of the flux meter (margin: how far outside
  // the grid particles are tracked, m).
  void start_flux(Level& parent, Real margin);
  IntervalFlux finish_flux(Level& parent);
  // Child: books an interval of the parent's crossings (inflow fed, outflow debited); `beyond`:
  // per face, the velocity given to what is placed there, the parent's bulk velocity at the face
  // (its Favre velocity in the face's cell). Not the crossings' mean: the particles that cross a
  // face in an interval are weighted by their speed, and by their fluctuation in and out again,
  // so their mean runs far ahead of the bulk (3 x in the jam study's silo), while placed
  // particles fill a volume, whose grains move as the bulk does
  // (docs/studies/mlcg_jam/NOTES.md, stop 28).
  void book(const IntervalFlux& flux, const std::vector<Vec3>& beyond);
  // Child: per face, the mass of the child's particles that left the region through it.
  void credit(const std::vector<Real>& left);
  // Collective: pays the faces' debts by removing the child's particles in each indebted face's
  // shell, nearest the face first; returns the mass removed (kg).
  Real extract(Level& child);
  // Collective (over both levels): places what the faces owe the child, only where the parent's
  // material reaches (insert_flux); returns the number of particles placed.
  std::int64_t insert(Level& child, const Level& parent);
  // Collective: removes parent particles in the region cells, one at a time while the next one's
  // mass fits the remaining `budget` (kg), each from the cell with the largest remaining
  // `excess` (kg per grid cell: how much more the parent holds there than the child; reduced by
  // each removal), the one nearest the cell's centre; once no cell has excess left, the ones
  // nearest to `near`. Returns the mass removed.
  Real remove_shadow(Level& parent, std::vector<Real> excess, const Vec3& near, Real budget);

  const std::vector<FluxInserter>& inserters() const { return inserters_; }
  std::vector<FluxInserter>& inserters() { return inserters_; }

  // Averages on the exchange grid (`child` false: the parent's averager).
  void sample(Level& level, bool child);
  CellFields finish_average(Level& level, bool child);

 private:
  InterfaceSpec spec_;
  std::shared_ptr<const ExchangeGrid> grid_;
  FaceFluxMeter meter_;
  std::vector<FluxInserter> inserters_;
  CellAverager parent_average_, child_average_;
};

}  // namespace grainscale
