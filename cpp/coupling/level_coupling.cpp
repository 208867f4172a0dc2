// The coupling forces as a level's force hook, and the calls that reach them by index.
#include "coupling/level_coupling.hpp"

#include <memory>
#include <string>

#include "core/errors.hpp"

namespace grainscale {

void CouplingHook::apply(ParticleStore& ps, const Domain& domain, Real dt,
                         const Communicator& comm) {
  const std::vector<Real> scale = coupling_push_scale(forces_, ps, domain, comm);
  forces_.apply(ps, dt, scale);
}

std::vector<Real> coupling_push_scale(const CouplingForces& c, const ParticleStore& ps,
                                      const Domain& domain, const Communicator& comm) {
  c.locate(ps, domain);
  if (c.pressure.empty()) return {};  // no stress condition (every rank alike): nothing pushed
  std::vector<Real> total = c.push_total();
  comm.sum_in_place(total);
  return c.push_scale(total);
}

int add_coupling(Level& level, CouplingForces forces) {
  return level.add_force_hook(std::make_shared<CouplingHook>(std::move(forces)));
}

CouplingForces& coupling(Level& level, int index) {
  const int n = level.force_hook_count();
  CouplingHook* hook =
      index >= 0 && index < n ? dynamic_cast<CouplingHook*>(&level.force_hook(index)) : nullptr;
  if (!hook) throw_invalid("coupling index", "in [0, " + std::to_string(n) + ")", index);
  return hook->forces();
}

std::vector<Real> coupling_push_moment(Level& level, int index) {
  const CouplingForces& c = coupling(level, index);
  std::vector<Real> moment =
      c.push_moment(coupling_push_scale(c, level.particles(), level.domain(), level.comm()));
  level.comm().sum_in_place(moment);
  return moment;
}

}  // namespace grainscale
