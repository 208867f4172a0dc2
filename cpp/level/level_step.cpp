// Level: the order of a step — set-up checks, list rebuilds (sorting, ghosts, lists, carried
// histories), force evaluation (force hooks, pair and wall loops, ghost force exchange) and the
// velocity Verlet steps of run() with the insertion hook between drift and forces.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "contact/pair_loop.hpp"
#include "contact/wall_loop.hpp"
#include "core/errors.hpp"
#include "integrate/time_step.hpp"
#include "integrate/velocity_verlet.hpp"
#include "level/level.hpp"

namespace grainscale {

namespace {

// Adds the wall-clock time of its scope to `total`.
class ScopedTimer {
 public:
  explicit ScopedTimer(double& total) : total_(total), start_(std::chrono::steady_clock::now()) {}
  ~ScopedTimer() {
    total_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  double& total_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace

void Level::prepare() {
  if (!law_prepared_) {
    const std::vector<Interaction> table = interaction_table();
    std::visit([&](auto& law) { law.prepare(materials_, table); }, law_);
    walls_.set_law_materials(materials_);
    const int stride = history_size(law_);
    contacts_.pairs.history_stride = stride;
    contacts_.walls.history_stride = stride;
    law_prepared_ = true;
  }
  ensure_decomposition();
  if (!(dt_ > 0)) throw_invalid("Simulation.time_step", "set to a positive value (s)", dt_);
  if (!(skin_ > 0)) throw_invalid("Simulation.skin", "set to a positive value (m)", skin_);
  if (!force_dt_ && comm_.any(ps_.n_owned() > 0)) {
    const Real t_r = smallest_rayleigh_time();
    if (dt_ > kMaxRayleighFraction * t_r) {
      std::ostringstream c;
      c.precision(6);
      c << "at most 0.3 x the smallest Rayleigh time (" << kMaxRayleighFraction * t_r
        << " s); pass force_time_step=True to override";
      throw_invalid("Simulation.time_step", c.str(), dt_);
    }
  }
  validate_periodic_lengths();
}

void Level::validate_periodic_lengths() const {
  Real r_max = 0;
  for (Index i = 0; i < ps_.n_owned(); ++i) r_max = std::max(r_max, ps_.radius[i]);
  const Real cutoff = 2 * comm_.max(r_max) + skin_;
  for (int a = 0; a < 3; ++a)
    if (domain_.periodic[a] && domain_.length()[a] < 2 * cutoff) {
      std::ostringstream c;
      c << "at least 2 x (largest diameter + skin) = " << 2 * cutoff << " m along periodic axis "
        << "xyz"[a];
      throw_invalid("Box.hi - Box.lo", c.str(), domain_.length()[a]);
    }
}

void Level::save_histories() {
  // Key every entry by its partner (global id / wall index) while the indices are valid.
  ContactList& pairs = contacts_.pairs;
  ContactList& walls = contacts_.walls;
  contacts_.pair_carry.save(pairs, PartnerKey{ps_.id.data()});
  contacts_.wall_carry.save(walls, PartnerKey{});
  std::vector<Index>& origin = contacts_.origin;
  origin.resize(ps_.n_owned());
  for (Index i = 0; i < ps_.n_owned(); ++i) origin[i] = i;
  pairs.partner.clear();
  walls.partner.clear();
}

void Level::rebuild() {
  const auto started = std::chrono::steady_clock::now();
  std::string unstable;
  for (Index i = 0; i < ps_.n_owned() && unstable.empty(); ++i)
    if (!ps_.position[i].allFinite() || !ps_.velocity[i].allFinite()) {
      std::ostringstream msg;
      msg << "particle " << ps_.id[i] << " has a non-finite position or velocity at step " << step_
          << ": the simulation is unstable (time step too large for the stiffness?)";
      unstable = msg.str();
    }
  comm_.raise_if_any(unstable);  // every rank raises, none waits in the exchanges below
  if (lists_valid_) save_histories();
  ps_.clear_ghosts();
  ghosts().clear();
  wrap_periodic(ps_, domain_);
  drop_lost();
  ensure_decomposition();

  Real r_max = 0, r_min = INFINITY;
  for (Index i = 0; i < ps_.n_owned(); ++i) {
    r_max = std::max(r_max, ps_.radius[i]);
    r_min = std::min(r_min, ps_.radius[i]);
  }
  r_max = comm_.max(r_max);
  r_min = comm_.min(r_min);
  guard_r_min_ = r_min;  // particles inserted in a run bring their radii
  update_guard_limit();
  const Real cutoff = 2 * r_max + skin_;
  const Real size_ratio = r_max / r_min;
  if (comm_.parallel()) partition_.redistribute(step_, cutoff, ps_, contacts_, domain_, comm_);

  // Spatial sort (owned particles in cell order, for cache locality in the force loop).
  grid_.build_for_pairs(ps_.position.data(), ps_.n_owned(), cutoff, size_ratio);
  std::vector<Index>& order = scratch_order_;
  order.assign(grid_.particles.begin(), grid_.particles.end());
  ps_.select_owned(order);
  std::vector<Index>& origin = contacts_.origin;
  std::vector<Index>& new_origin = scratch_index_;
  new_origin.resize(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) new_origin[k] = origin[order[k]];
  origin.swap(new_origin);

  ghosts().build(ps_, domain_, partition_.decomposition(), comm_, cutoff);
  // Without ghosts the sorted particles fill the same cells in order: the grid only needs
  // renumbering, not a second binning.
  if (ps_.n_ghost() == 0)
    grid_.renumber_sorted();
  else
    grid_.build_for_pairs(ps_.position.data(), ps_.n_local(), cutoff, size_ratio);
  ContactList& pairs = contacts_.pairs;
  ContactList& walls = contacts_.walls;
  build_pair_list(ps_, grid_, cutoff, skin_, pairs);
  walls_.build_mesh_bins(r_max + skin_, cutoff);
  build_wall_list(ps_, walls_.walls(), walls_.primitives().first, skin_, walls);

  contacts_.pair_carry.restore(origin, PartnerKey{ps_.id.data()}, pairs);
  contacts_.wall_carry.restore(origin, PartnerKey{}, walls);
  contacts_.pair_carry.clear();
  contacts_.wall_carry.clear();

  x_at_build_.assign(ps_.position.data(), ps_.position.data() + ps_.n_owned());
  drift_bound_ = 0;
  walls_.reset_shift();
  lists_valid_ = true;
  ++rebuilds_;
  rebuild_seconds_ +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
}

template <class Law, bool kUpdate, bool kStats, bool kOwnedReset>
void Level::compute_forces(const Law& law, bool defer_reverse) {
  const Index n = ps_.n_owned();
  if constexpr (!kOwnedReset)
    for (Index i = 0; i < n; ++i) {
      ps_.force[i] = ps_.mass[i] * gravity_;
      ps_.torque[i].setZero();
    }
  for (Index g = n; g < ps_.n_local(); ++g) {
    ps_.force[g].setZero();
    ps_.torque[g].setZero();
  }
  walls_.reset_loads();
  for (const std::shared_ptr<ForceHook>& hook : force_hooks_) hook->apply(ps_, domain_, dt_, comm_);
  if constexpr (kStats) stats_.clear();
  accumulate_pair_forces<Law, kUpdate, kStats>(law, ps_, contacts_.pairs, dt_, stats_);
  // The ghost forces travel while the walls are computed (and, deferred, while the particles
  // that did not send ghosts are integrated); walls act on owned particles only.
  GhostExchange& halo = partition_.ghosts();
  halo.reverse_begin(ps_, comm_);
  accumulate_wall_forces<Law, kUpdate, kStats>(law, ps_, walls_.walls(), walls_.primitives(),
                                               contacts_.walls, dt_, stats_);
  if (defer_reverse && !halo.deferred().empty()) {
    reverse_pending_ = true;
  } else {
    const ScopedTimer timer(halo_seconds_);
    halo.reverse_end(ps_, comm_);
  }
  if (comm_.parallel()) {
    const ScopedTimer timer(halo_seconds_);
    // Servo walls move by the total load every step; other loads are read after a run.
    if (kStats || walls_.any_servo()) walls_.reduce_loads(comm_);
    if constexpr (kStats) reduce_stats();
  }
}

template <bool kPlanar, class Law>
bool Level::run_with(const Law& law, std::int64_t steps, bool stats) {
  // Ranks agree first: one rank's particles changed from Python means every rank rebuilds.
  // A set-up evaluation with valid lists first refreshes the ghosts: their velocities are those
  // of the last force evaluation, not of the closing kick or of changes made from Python.
  if (comm_.any(!lists_valid_))
    rebuild();
  else if (comm_.any(!forces_valid_))
    ghosts().forward(ps_, comm_);
  if (comm_.any(!forces_valid_)) compute_forces<Law, false, true, false>(law);
  forces_valid_ = true;
  const Real half_skin = 0.5 * skin_;
  bool stopped = false;
  for (std::int64_t s = 0; s < steps; ++s) {
    // The previous step's closing half kick is fused into this pass (velocity_verlet.hpp),
    // which also resets the owned forces to m g.
    Real max_v2;
    if (reverse_pending_) {
      // The particles whose forces are complete move first, the others once theirs arrived.
      max_v2 = kick_drift_except<kPlanar>(ps_, dt_, gravity_, ghosts().deferred_mask());
      {
        const ScopedTimer timer(halo_seconds_);
        ghosts().reverse_end(ps_, comm_);
      }
      reverse_pending_ = false;
      max_v2 =
          larger_or_nan(max_v2, kick_drift_only<kPlanar>(ps_, dt_, gravity_, ghosts().deferred()));
    } else {
      max_v2 = s == 0 ? kick_drift<kPlanar, false>(ps_, dt_, gravity_)
                      : kick_drift<kPlanar, true>(ps_, dt_, gravity_);
    }
    const Real wall_shift = walls_.advance(dt_);
    ++step_;
    time_ = time_at_dt_change_ + (step_ - step_at_dt_change_) * dt_;
    apply_insertions_and_outlets();  // may add/remove particles: lists become invalid
    // Inserted particles start with zero force: then the owned forces are set again.
    const bool owned_reset = lists_valid_;
    // Step guard (guards.hpp): one compare of the drift's largest speed with the bound from the
    // smallest radius (NaN fails it); only then are the particles scanned for the offender.
    const bool guard_hit = guards_.enabled && !(max_v2 <= guard_speed2_) && step_guard_hit();
    // One reduction decides for all ranks (a rank that inserted or removed particles, or whose
    // guard tripped, counts as having moved infinitely far; NaN becomes infinity too). The list
    // is rebuilt when a particle has moved more than half the skin since the last build: the
    // drift speeds bound the displacements, and only when the bound reaches half the skin are
    // they measured (the same decisions as measuring every step, without reading the build
    // positions each step).
    Real speed2_all;
    {
      const ScopedTimer timer(halo_seconds_);
      speed2_all = comm_.max(lists_valid_ && !guard_hit ? max_v2 : INFINITY);
    }
    // Rare (insertions, removals, a guard): do the ranks agree on a guard? Stops at once for a
    // non-finite value, else after this step.
    const bool stop = guards_.enabled && !(speed2_all < INFINITY) && agree_step_guard(guard_hit);
    drift_bound_ += dt_ * std::sqrt(speed2_all);
    bool stale = !(drift_bound_ + wall_shift <= half_skin);
    if (stale && std::isfinite(speed2_all)) {
      const Real moved2 = max_displacement2(ps_, x_at_build_);
      Real moved2_all;
      {
        const ScopedTimer timer(halo_seconds_);
        moved2_all = comm_.max(moved2);
      }
      drift_bound_ = std::sqrt(moved2_all);
      stale = !(drift_bound_ + wall_shift <= half_skin);
    }
    if (stale) {
      rebuild();
    } else {
      const ScopedTimer timer(halo_seconds_);
      ghosts().forward(ps_, comm_);
    }
    // Only a step followed by another in this run leaves its ghost forces travelling.
    const bool last = s + 1 == steps || stop;
    if (last && stats)
      compute_forces<Law, true, true, false>(law);
    else if (owned_reset)
      compute_forces<Law, true, false, true>(law, !last);
    else
      compute_forces<Law, true, false, false>(law, !last);
    if (stop) {
      stopped = true;
      steps = s + 1;
      break;
    }
  }
  // The wall loads are read after a run: summed over the ranks at the last step in any case.
  if (steps > 0 && !stats && comm_.parallel() && !walls_.any_servo()) {
    const ScopedTimer timer(halo_seconds_);
    walls_.reduce_loads(comm_);
  }
  if (steps > 0) kick<kPlanar>(ps_, dt_);
  return stopped;
}

void Level::refresh_forces() {
  std::visit(
      [&](const auto& law) {
        if (comm_.any(!lists_valid_))
          rebuild();
        else if (comm_.any(!forces_valid_))
          ghosts().forward(ps_, comm_);  // as in run_with: ghosts as fresh as their owners
        if (comm_.any(!forces_valid_))
          compute_forces<std::decay_t<decltype(law)>, false, true, false>(law);
      },
      law_);
  forces_valid_ = true;
}

void Level::apply_insertions_and_outlets() {
  // The step evaluates the forces of every particle right after this hook, so adding or removing
  // particles here must not mark the forces invalid: that would make the next run() re-evaluate
  // them (without history update) and the result depend on how run() is chunked.
  const bool forces_valid = forces_valid_;
  insertion_.step(*this);
  forces_valid_ = forces_valid;
}

void Level::run(std::int64_t steps, bool stats) {
  if (steps < 0) throw_invalid("Simulation.run.steps", "non-negative", steps);
  prepare();
  start_guards();
  // The overlap guard reads the contact statistics of the last step.
  const bool stats_needed = stats || guards_.enabled;
  bool stopped = false;
  std::visit(
      [&](const auto& law) {
        if (dimension_ == 2)
          stopped = run_with<true>(law, steps, stats_needed);
        else
          stopped = run_with<false>(law, steps, stats_needed);
      },
      law_);
  if (stopped) raise_guard(guard_message_, step_fallback());
  if (guards_.enabled && steps > 0) check_overlap_guard();
}

}  // namespace grainscale
