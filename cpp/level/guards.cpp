// Guards (level/guards.hpp): the rare paths that find the offender once a bound is exceeded, and
// the Level's per-step and per-run checks (called from level_step.cpp).
#include "level/guards.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "contact/wall_loop.hpp"
#include "core/errors.hpp"
#include "level/level.hpp"

namespace grainscale {

std::string find_step_violation(const ParticleStore& ps, Real dt, Real fraction, std::int64_t step,
                                bool& fatal) {
  Index worst = -1;
  Real worst_ratio = fraction;
  for (Index i = 0; i < ps.n_owned(); ++i) {
    if (!ps.position[i].allFinite() || !ps.velocity[i].allFinite()) {
      std::ostringstream msg;
      msg << "particle " << ps.id[i] << " has a non-finite position or velocity at step " << step
          << " (x = (" << ps.position[i].transpose() << ") m, v = (" << ps.velocity[i].transpose()
          << ") m/s): the simulation is unstable";
      fatal = true;
      return msg.str();
    }
    const Real ratio = dt * ps.velocity[i].norm() / ps.radius[i];
    if (ratio > worst_ratio) {
      worst = i;
      worst_ratio = ratio;
    }
  }
  fatal = false;
  if (worst < 0) return {};
  std::ostringstream msg;
  msg.precision(6);
  const Real r = ps.radius[worst];
  msg << "particle " << ps.id[worst] << " moved " << worst_ratio * r << " m in step " << step
      << ", " << worst_ratio << " x its radius " << r << " m (limit " << fraction
      << " x the radius, Guards.max_step_displacement): it may pass through walls and "
         "particles unseen";
  return msg.str();
}

OverlapFinding largest_overlap(const ParticleStore& ps, const ContactList& pairs,
                               const ContactList& walls, const std::vector<Wall>& wall_list,
                               const WallPrimitives& primitives) {
  OverlapFinding best;
  const Index n = ps.n_owned();
  if (pairs.first.size() == static_cast<std::size_t>(n) + 1)
    for (Index i = 0; i < n; ++i)
      for (Index k = pairs.first[i]; k < pairs.first[i + 1]; ++k) {
        const Index j = pairs.partner[k];
        const Real ri = ps.radius[i], rj = ps.radius[j];
        const Real overlap = ri + rj - (ps.position[i] - ps.position[j]).norm();
        const Real ratio = overlap / std::min(ri, rj);
        if (ratio > best.ratio) best = {ratio, ps.id[i], ps.id[j]};
      }
  if (walls.first.size() == static_cast<std::size_t>(n) + 1)
    for (Index i = 0; i < n; ++i)
      for (Index k = walls.first[i]; k < walls.first[i + 1]; ++k) {
        const int p = walls.partner[k];
        const int w = primitives.wall[p];
        const Wall& wall = wall_list[w];
        const Vec3& x = ps.position[i];
        Real distance;
        if (wall.shape == WallShape::Mesh) {
          distance = (x - wall.mesh->closest(p - primitives.first[w], x).point).norm();
        } else {
          WallContact g;
          if (!wall.closest(x, g)) continue;
          distance = g.distance;
        }
        const Real ratio = (ps.radius[i] - distance) / ps.radius[i];
        if (ratio > best.ratio) best = {ratio, ps.id[i], -1 - GlobalId(w)};
      }
  return best;
}

void Level::set_guards(const GuardLimits& limits) {
  if (!(limits.max_step_displacement > 0) || !std::isfinite(limits.max_step_displacement))
    throw_invalid("Guards.max_step_displacement", "a positive fraction of the particle radius",
                  limits.max_step_displacement);
  if (!(limits.max_overlap > 0) || !std::isfinite(limits.max_overlap))
    throw_invalid("Guards.max_overlap", "a positive fraction of the smaller radius",
                  limits.max_overlap);
  guards_ = limits;
  update_guard_limit();
}

void Level::update_guard_limit() {
  const Real reach = guards_.max_step_displacement * guard_r_min_ / dt_;
  guard_speed2_ = reach * reach;  // +inf without particles (r_min = inf), 0 before dt is set
}

void Level::start_guards() {
  guard_tripped_ = false;
  guard_message_.clear();
  if (!guards_.enabled) return;
  Real r_min = INFINITY;
  for (Index i = 0; i < ps_.n_owned(); ++i) r_min = std::min(r_min, ps_.radius[i]);
  guard_r_min_ = comm_.min(r_min);
  update_guard_limit();
  check_wall_speeds();
}

void Level::check_wall_speeds() const {
  // Walls are the same on every rank, and so is the smallest radius: all ranks throw alike.
  const Real limit = guards_.max_step_displacement * guard_r_min_;
  const auto& walls = walls_.walls();
  for (std::size_t k = 0; k < walls.size(); ++k) {
    const Real moved = walls[k].step_bound(dt_, walls_.reach(static_cast<int>(k)));
    if (!(moved > limit)) continue;
    std::ostringstream msg;
    msg.precision(6);
    msg << "guard stopped the run before step " << step_ << ": wall " << k << " moves up to "
        << moved << " m per step (speed and rotation x dt " << dt_
        << " s), more than max_step_displacement " << guards_.max_step_displacement
        << " x the smallest radius " << guard_r_min_
        << " m: particles could pass through it unseen; reduce the time step or the wall's "
           "speed";
    throw std::runtime_error(msg.str());
  }
}

bool Level::step_guard_hit() {
  guard_message_ =
      find_step_violation(ps_, dt_, guards_.max_step_displacement, step_, guard_fatal_);
  return !guard_message_.empty();
}

std::string Level::step_fallback() const {
  return "a particle moved more than " + shortest(guards_.max_step_displacement) +
         " x its radius or became non-finite at step " + std::to_string(step_);
}

bool Level::agree_step_guard(bool hit) {
  const std::int64_t worst = comm_.max(std::int64_t(hit ? (guard_fatal_ ? 2 : 1) : 0));
  if (worst == 0) return false;
  if (worst == 2) {
    // Non-finite values: the step cannot be finished (a list build would fail on them).
    lists_valid_ = false;
    forces_valid_ = false;
    raise_guard(guard_fatal_ ? guard_message_ : std::string(), step_fallback());
  }
  return true;
}

void Level::raise_guard(const std::string& message, const std::string& fallback) {
  const Real t_r = smallest_rayleigh_time();  // collective: before the ranks part
  // No rank found the offender (cannot happen unless rounding differs): the same text on all.
  const bool found = comm_.any(!message.empty());
  const std::string& cause = found ? message : fallback;
  guard_tripped_ = true;
  std::string full;
  if (!cause.empty()) {
    std::ostringstream msg;
    msg.precision(6);
    msg << "guard stopped the run: " << cause << "; reduce the time step (now " << dt_
        << " s, smallest Rayleigh time " << t_r << " s) or check for initial overlaps";
    full = msg.str();
  }
  comm_.raise_if_any(full);
  throw std::runtime_error("guard stopped the run");  // not reached: the fallback is never empty
}

void Level::check_overlap_guard() {
  // max_overlap_ratio was reduced over the ranks: every rank takes the same branch.
  if (!(stats_.max_overlap_ratio > guards_.max_overlap)) return;
  const OverlapFinding found =
      largest_overlap(ps_, contacts_.pairs, contacts_.walls, walls_.walls(), walls_.primitives());
  const Real ratio_all = comm_.max(found.ratio);
  std::string message;
  if (found.a >= 0 && found.ratio == ratio_all) {
    std::ostringstream msg;
    msg.precision(6);
    msg << "particle " << found.a;
    if (found.b >= 0)
      msg << " overlaps particle " << found.b << " by " << found.ratio << " x the smaller radius";
    else
      msg << " overlaps wall " << -1 - found.b << " by " << found.ratio << " x its radius";
    msg << " at step " << step_ << " (limit " << guards_.max_overlap
        << ", Guards.max_overlap): the contact force is far outside the contact law's range";
    message = msg.str();
  }
  std::ostringstream fallback;
  fallback << "a contact overlaps by " << stats_.max_overlap_ratio
           << " x the smaller radius at step " << step_ << " (limit " << guards_.max_overlap
           << ", Guards.max_overlap)";
  raise_guard(message, fallback.str());
}

}  // namespace grainscale
