// The coupling forces of a hierarchy plugged into a level: a ForceHook (level/force_hook.hpp)
// that applies one CouplingForces at every force evaluation of the level, with the push scale
// summed over the ranks, and the calls that add and reach those forces by their index (the
// bindings' Level.add_coupling, set_coupling_*, coupling_push_moment).
#pragma once

#include <vector>

#include "coupling/coupling_forces.hpp"
#include "level/force_hook.hpp"
#include "level/level.hpp"

namespace grainscale {

class CouplingHook final : public ForceHook {
 public:
  explicit CouplingHook(CouplingForces forces) : forces_(std::move(forces)) {}
  CouplingForces& forces() { return forces_; }
  void apply(ParticleStore& ps, const Domain& domain, Real dt, const Communicator& comm) override;

 private:
  CouplingForces forces_;
};

// Locates the particles of `ps` for `c` and returns the scale of each face's push (collective:
// sums the push totals over the ranks).
std::vector<Real> coupling_push_scale(const CouplingForces& c, const ParticleStore& ps,
                                      const Domain& domain, const Communicator& comm);
// Adds coupling forces to `level` (applied every step after the force reset); returns the index.
int add_coupling(Level& level, CouplingForces forces);
// The coupling forces of that index; throws InvalidArgument for an unknown index.
CouplingForces& coupling(Level& level, int index);
// Collective: coupling(index).push_moment summed over the ranks (N m per interface face).
std::vector<Real> coupling_push_moment(Level& level, int index);

}  // namespace grainscale
