#include "coupling/interface.hpp"

namespace grainscale {

Interface::Interface(const InterfaceSpec& spec, const Domain& parent_domain, int dimension)
    : spec_(spec),
      grid_(std::make_shared<const ExchangeGrid>(spec.region, spec.cell_size, parent_domain,
                                                 "Exchange")),
      parent_average_(grid_->grid(), dimension),
      child_average_(grid_->grid(), dimension) {
  const auto& faces = grid_->faces();
  inserters_.reserve(faces.size());
  for (std::size_t f = 0; f < faces.size(); ++f)
    inserters_.emplace_back(faces[f], grid_->grid(), spec.fine_radius, spec.fine_density,
                            spec.fine_material, spec.size_ratio, spec.seed + 7919 * f);
}

void Interface::start_flux(Level& parent, Real margin) {
  meter_.start(parent.particles(), *grid_, parent.domain(), margin, parent.comm());
}

std::vector<FaceFlux> Interface::finish_flux(Level& parent) {
  return meter_.finish(parent.particles(), *grid_, parent.domain(), parent.comm());
}

void Interface::feed(const std::vector<FaceFlux>& fluxes) {
  if (fluxes.size() != inserters_.size())
    throw std::invalid_argument("Interface.feed: one flux per interface face expected");
  for (std::size_t f = 0; f < fluxes.size(); ++f) {
    const FaceFlux& x = fluxes[f];
    if (!(x.mass > 0)) continue;
    const Vec3 spin = x.inertia > 0 ? Vec3(x.spin / x.inertia) : Vec3::Zero();
    inserters_[f].feed(x.mass, x.momentum / x.mass, spin);
  }
}

std::int64_t Interface::insert(Level& child) { return child.insert_flux(inserters_); }

void Interface::sample(Level& level, bool child) {
  (child ? child_average_ : parent_average_)
      .sample(level.particles(), level.last_stats(), level.domain());
}

CellFields Interface::finish_average(Level& level, bool child) {
  return (child ? child_average_ : parent_average_).finish(level.comm());
}

}  // namespace grainscale
