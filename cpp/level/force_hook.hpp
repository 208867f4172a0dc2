// ForceHook: how a higher floor adds forces to a level's particles every step (the hierarchy's
// coupling forces, coupling/level_coupling.hpp). The level calls apply() on every hook, in the
// order they were added, once per force evaluation: after the forces are reset to gravity (and
// the wall loads to zero), before the contacts. A hook is collective (every rank calls it at the
// same point) and adds to the owned particles only.
#pragma once

#include "core/types.hpp"
#include "parallel/communicator.hpp"
#include "state/domain.hpp"
#include "state/particle_store.hpp"

namespace grainscale {

class ForceHook {
 public:
  virtual ~ForceHook() = default;
  // dt: the level's time step.
  virtual void apply(ParticleStore& ps, const Domain& domain, Real dt,
                     const Communicator& comm) = 0;
};

}  // namespace grainscale
