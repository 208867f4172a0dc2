// The forces one level of a hierarchy feels from another (DESIGN.md 4), applied every step
// after the force reset, before the contacts; both are set per exchange interval by the
// hierarchy's controllers (python/grainscale/hierarchy.py) on the cells of one ExchangeGrid.
//
// Fine -> coarse, velocity feedback: every owned particle in cell c gets F = m a_c, the cell's
// acceleration towards the fine Favre velocity (zero outside the coupled cells). With velocity
// bounds per cell (the fine level's velocity range there), each component of a_c is scaled down
// for a particle so that one step of it, a dt, does not carry the particle's velocity beyond the
// bound it points to (the per-particle limiter of the reference implementation, LIGGGHTS-PFM's
// fix forcecontrol/region, applied per component): the push follows the fine level's velocities,
// whatever the coarse particle's own motion, so it can set a bed at rest in motion.
//
// Coarse -> fine, stress boundary condition: a particle within `layer` of an interface face
// (inside the region, in that face's cell) is pushed along the face's inward normal with
//   F = p_f pi r^2 w(s),   w = 1 for s <= layer - fade,  w = sin^2(pi/2 (layer - s) / fade)
// up to s = layer (s: distance from the face), so the pushing layer ends smoothly; p_f >= 0 is
// the face's controller output (Pa; never pulling). A particle already moving inward faster than
// the face's `max_inward_speed` is not pushed (the velocity limiter).
//
// The push stands for the contacts the fine particles would have with the material beyond the
// face; push_moment() gives, per face, the virial those contacts would add to the face's cell,
// sum_i |F_i| s_i (N m; branch vector from the face to the centre), which the controller adds to
// the cell's contact virial: without it the cell average misses the load the pushed layer
// carries over its thickness and the controller overloads the cells inside.
#pragma once

#include <memory>
#include <vector>

#include "field/exchange_grid.hpp"
#include "state/domain.hpp"
#include "state/particle_store.hpp"

namespace grainscale {

class CouplingForces {
 public:
  CouplingForces(std::shared_ptr<const ExchangeGrid> grid, Real layer, Real fade);

  const ExchangeGrid& grid() const { return *grid_; }
  // Per cell (m/s^2); empty: no velocity feedback.
  std::vector<Vec3> acceleration;
  // Per cell (m/s), the limiter's bounds of the feedback; empty: no limiter.
  std::vector<Vec3> velocity_min, velocity_max;
  // Per interface face (Pa, >= 0) and the limiter's speed (m/s); empty: no stress condition.
  std::vector<Real> pressure;
  std::vector<Real> max_inward_speed;

  // The push of a face totals pressure x area whatever its layer's packing: each particle's
  // p pi r^2 w is scaled by p A / sum(p pi r^2 w) over the layer (at most kMaxPushScale, so that
  // a few particles in an almost empty layer are not shot into the bed).
  static constexpr Real kMaxPushScale = 4;
  // One pass over the owned particles of `ps`: the cell of each one inside the grid and every
  // push it feels, kept for the calls below, which act on the particles as last located (the
  // cell lookup is the main cost of the coupling forces: once per step, not once per call).
  void locate(const ParticleStore& ps, const Domain& domain) const;
  // Per interface face: sum over the located particles of p pi r^2 w (N), this rank only (needs
  // `pressure` set).
  std::vector<Real> push_total() const;
  // Per interface face: the scale of its push, from the totals summed over every rank (needs
  // `pressure` set).
  std::vector<Real> push_scale(const std::vector<Real>& total) const;
  // Adds the forces to the owned particles of `ps` (dt: the level's time step, for the limiter;
  // scale: push_scale of the rank-summed push_total, read only when `pressure` is set).
  // Each particle gets its feedback force first, then its pushes face by face.
  void apply(ParticleStore& ps, Real dt, const std::vector<Real>& scale) const;
  // Per interface face: sum over the located particles of |F_push| s (N m), this rank only.
  std::vector<Real> push_moment(const std::vector<Real>& scale) const;

 private:
  std::shared_ptr<const ExchangeGrid> grid_;
  Real layer_ = 0, fade_ = 0;

  struct Push {
    Index particle;
    int face;
    Real magnitude;  // p pi r^2 w (N), before the face's scale
    Real depth;      // s (m)
  };
  // Of the last locate(), in particle order: (particle, cell) inside the grid, and the pushes.
  mutable std::vector<std::pair<Index, int>> inside_;
  mutable std::vector<Push> pushes_;
};

}  // namespace grainscale
