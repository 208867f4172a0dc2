// Interface: the coupling between a level of a hierarchy (the parent) and the finer level
// embedded in a region of it (the child), DESIGN.md 4. It holds the ExchangeGrid of the region,
// the parent's face flux meter, the child's flux inserters (one per interface face) and a cell
// averager on each side; the hierarchy (python/grainscale/hierarchy.py) calls it once per
// exchange interval and computes the controllers from the averages. Every call that takes a
// Level is collective over that level's ranks.
#pragma once

#include <memory>
#include <vector>

#include "coupling/exchange_grid.hpp"
#include "coupling/face_flux.hpp"
#include "coupling/flux_inserter.hpp"
#include "field/cell_average.hpp"
#include "level/level.hpp"

namespace grainscale {

struct InterfaceSpec {
  Region region = Region::box(Vec3::Zero(), Vec3::Ones());
  Real cell_size = 0;  // m
  SizeDistribution fine_radius = SizeDistribution::monodisperse(1);
  Real fine_density = 0;  // kg/m^3
  std::int32_t fine_material = 0;
  Real size_ratio = 1;  // parent / child particle size (h_parent / h_child)
  std::uint64_t seed = 0;
  Real layer = 0, fade = 0;  // stress layer thickness and its fade (m)
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
  std::vector<FaceFlux> finish_flux(Level& parent);
  // Child: books the fluxes at the faces' inserters and places what they owe; returns the
  // number of fine particles placed now.
  void feed(const std::vector<FaceFlux>& fluxes);
  std::int64_t insert(Level& child);
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
