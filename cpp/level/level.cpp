#include "level/level.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "contact/pair_loop.hpp"
#include "contact/wall_loop.hpp"
#include "core/errors.hpp"
#include "integrate/time_step.hpp"
#include "integrate/velocity_verlet.hpp"
#include "parallel/migration.hpp"
#include "state/body_shape.hpp"

namespace grainscale {

Level::Level(const Domain& domain, Communicator comm)
    : domain_(domain),
      law_(make_contact_law("hertz", "none", ContactSettings{})),
      comm_(std::move(comm)) {
  if (comm_.parallel()) balance_every_ = 500;
}

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

void validate(const Interaction& in) {
  if (!(in.restitution >= 0 && in.restitution <= 1))
    throw_invalid("restitution", "in [0, 1]", in.restitution);
  if (!(in.friction >= 0) || !std::isfinite(in.friction))
    throw_invalid("friction", "non-negative and finite", in.friction);
  if (!(in.rolling_friction >= 0) || !std::isfinite(in.rolling_friction))
    throw_invalid("rolling_friction", "non-negative and finite", in.rolling_friction);
  if (!(in.rolling_damping >= 0) || !std::isfinite(in.rolling_damping))
    throw_invalid("rolling_damping", "non-negative and finite", in.rolling_damping);
  if (!(in.normal_stiffness >= 0) || !std::isfinite(in.normal_stiffness))
    throw_invalid("normal_stiffness", "non-negative (N/m; 0 derives it)", in.normal_stiffness);
  if (!(in.tangential_stiffness >= 0) || !std::isfinite(in.tangential_stiffness))
    throw_invalid("tangential_stiffness", "non-negative (N/m; 0 means 2/7 k_n)",
                  in.tangential_stiffness);
  if (!(in.characteristic_velocity > 0) || !std::isfinite(in.characteristic_velocity))
    throw_invalid("characteristic_velocity", "positive (m/s)", in.characteristic_velocity);
  if (!(in.eepa_exponent == 1 || in.eepa_exponent == 1.5))
    throw_invalid("exponent", "1 or 1.5", in.eepa_exponent);
  if (!(in.loading_stiffness >= 0) || !std::isfinite(in.loading_stiffness))
    throw_invalid("loading_stiffness", "non-negative (0 derives it)", in.loading_stiffness);
  if (!(in.unloading_ratio >= 1) || !std::isfinite(in.unloading_ratio))
    throw_invalid("unloading_ratio", ">= 1 (k2/k1)", in.unloading_ratio);
  if (!(in.adhesive_stiffness >= 0) || !std::isfinite(in.adhesive_stiffness))
    throw_invalid("adhesive_stiffness", "non-negative", in.adhesive_stiffness);
  if (!std::isfinite(in.pull_off_force))
    throw_invalid("pull_off_force", "finite (N)", in.pull_off_force);
  if (!(in.adhesion_exponent > 0) || !std::isfinite(in.adhesion_exponent))
    throw_invalid("adhesion_exponent", "positive", in.adhesion_exponent);
}

}  // namespace

void Level::set_interaction(int i, int j, const Interaction& interaction) {
  for (int k : {i, j})
    if (k < -1 || k >= materials_.n_materials())
      throw_invalid("interaction material index", "-1 (rigid wall) or a known material", k);
  validate(interaction);
  interactions_[{std::min(i, j), std::max(i, j)}] = interaction;
  law_prepared_ = false;
  forces_valid_ = false;
}

void Level::set_default_interaction(const Interaction& interaction) {
  validate(interaction);
  default_interaction_ = interaction;
  law_prepared_ = false;
  forces_valid_ = false;
}

std::vector<Interaction> Level::interaction_table() const {
  const int stride = materials_.n_materials() + 1;
  std::vector<Interaction> table(static_cast<std::size_t>(stride) * stride, default_interaction_);
  auto index = [&](int k) { return k < 0 ? materials_.rigid_index() : k; };
  for (const auto& [key, in] : interactions_) {
    const int a = index(key.first), b = index(key.second);
    table[a * stride + b] = in;
    table[b * stride + a] = in;
  }
  return table;
}

int Level::add_material(const MaterialProperties& props) {
  const int index = materials_.add(props);
  law_prepared_ = false;
  return index;
}

void Level::set_contact_law(const ContactLaw& law) {
  if (lists_valid_) save_histories();
  law_ = law;
  law_prepared_ = false;
  lists_valid_ = false;
  forces_valid_ = false;
  // A different law has a different history layout: contacts restart from zero.
  pair_carry_ = HistoryCarry();
  wall_carry_ = HistoryCarry();
}

void Level::set_gravity(const Vec3& g) {
  if (!g.allFinite()) throw_invalid("Simulation.gravity", "finite (m/s^2)", g.transpose());
  gravity_ = g;
  forces_valid_ = false;
}

void Level::set_time_step(Real dt, bool force) {
  if (!(dt > 0) || !std::isfinite(dt))
    throw_invalid("Simulation.time_step", "positive and finite (s)", dt);
  time_at_dt_change_ = time_;
  step_at_dt_change_ = step_;
  dt_ = dt;
  force_dt_ = force;
}

void Level::set_dimension(int dimension) {
  if (dimension != 2 && dimension != 3) throw_invalid("Simulation.dimension", "2 or 3", dimension);
  if (next_id_ > 0 || !streams_.empty())
    throw_invalid("Simulation.dimension", "set before particles or streams are added", dimension);
  dimension_ = dimension;
}

void Level::set_skin(Real skin) {
  if (!(skin > 0) || !std::isfinite(skin))
    throw_invalid("Simulation.skin", "positive and finite (m)", skin);
  if (lists_valid_) save_histories();
  skin_ = skin;
  lists_valid_ = false;
}

void Level::mark_positions_changed() {
  if (lists_valid_) save_histories();
  lists_valid_ = false;
  forces_valid_ = false;
}

GlobalId Level::add_particles(Index n, const Real* position, const Real* velocity,
                              const Real* angular_velocity, const Real* radius,
                              const std::int32_t* material) {
  if (n < 0) throw_invalid("add_particles.count", "non-negative", n);
  for (Index k = 0; k < n; ++k) {
    const Vec3 x(position[3 * k], position[3 * k + 1], position[3 * k + 2]);
    if (!x.allFinite()) throw_invalid("add_particles.position", "finite (m)", x.transpose());
    for (int a = 0; a < 3; ++a)
      if (!domain_.periodic[a] && !domain_.inside(x, a)) {
        std::ostringstream range;
        range << "inside the domain [" << domain_.lo[a] << ", " << domain_.hi[a] << "] on axis "
              << "xyz"[a] << " (particle " << k << ")";
        throw_invalid("add_particles.position", range.str(), x[a]);
      }
    if (dimension_ == 2 && x[2] != plane_z()) {
      std::ostringstream c;
      c << "equal to the plane z = " << shortest(plane_z()) << " m of the 2-D mode (particle " << k
        << ")";
      throw_invalid("add_particles.position z", c.str(), x[2]);
    }
    if (!(radius[k] > 0) || !std::isfinite(radius[k]))
      throw_invalid("add_particles.radius", "positive and finite (m)", radius[k]);
    if (material[k] < 0 || material[k] >= materials_.n_materials())
      throw_invalid("add_particles.material", "a material index known to the simulation",
                    material[k]);
    if (!materials_.deformable(material[k]))
      throw_invalid("add_particles.material", "deformable (finite youngs_modulus)", material[k]);
    if (velocity && !Vec3(velocity[3 * k], velocity[3 * k + 1], velocity[3 * k + 2]).allFinite())
      throw_invalid("add_particles.velocity", "finite (m/s)", k);
    if (angular_velocity &&
        !Vec3(angular_velocity[3 * k], angular_velocity[3 * k + 1], angular_velocity[3 * k + 2])
             .allFinite())
      throw_invalid("add_particles.angular_velocity", "finite (rad/s)", k);
  }
  if (lists_valid_) save_histories();
  lists_valid_ = false;
  forces_valid_ = false;
  ps_.clear_ghosts();
  ghosts_.clear();
  ensure_decomposition();
  const GlobalId first = next_id_;
  std::vector<char> mine(n, 1);
  Index kept = n;
  if (comm_.parallel()) {
    kept = 0;
    for (Index k = 0; k < n; ++k) {
      mine[k] = owns(Vec3(position[3 * k], position[3 * k + 1], position[3 * k + 2]));
      kept += mine[k];
    }
  }
  ps_.reserve(ps_.n_owned() + kept);
  for (Index k = 0; k < n; ++k) {
    if (!mine[k]) {  // another rank's: its id is taken all the same
      ++next_id_;
      continue;
    }
    const Real r = radius[k];
    const Real m = particle_mass(materials_[material[k]].density, r, dimension_);
    const Vec3 x(position[3 * k], position[3 * k + 1], position[3 * k + 2]);
    Vec3 v =
        velocity ? Vec3(velocity[3 * k], velocity[3 * k + 1], velocity[3 * k + 2]) : Vec3::Zero();
    Vec3 w = angular_velocity ? Vec3(angular_velocity[3 * k], angular_velocity[3 * k + 1],
                                     angular_velocity[3 * k + 2])
                              : Vec3::Zero();
    if (dimension_ == 2) {  // a disc moves in its plane and spins about z only
      v[2] = 0;
      w[0] = w[1] = 0;
    }
    ps_.add_owned(next_id_++, x, v, w, r, m, particle_inertia(m, r, dimension_), material[k]);
    origin_.push_back(-1);
  }
  return first;
}

Real Level::kinetic_energy() const {
  Real e = 0;
  for (Index i = 0; i < ps_.n_owned(); ++i) {
    const Real m = ps_.mass[i];
    e += 0.5 * m * ps_.velocity[i].squaredNorm() +
         0.5 / ps_.inv_inertia[i] * ps_.angular_velocity[i].squaredNorm();
  }
  return comm_.sum(e);
}

Real Level::smallest_rayleigh_time() const {
  Real t = INFINITY;
  for (Index i = 0; i < ps_.n_owned(); ++i) {
    const MaterialProperties& m = materials_[ps_.material[i]];
    t = std::min(t, rayleigh_time(ps_.radius[i], m.density, m.youngs_modulus, m.poisson_ratio));
  }
  return comm_.min(t);
}

std::vector<std::array<GlobalId, 2>> Level::neighbor_pairs() const {
  std::vector<std::array<GlobalId, 2>> out;
  if (!lists_valid_) return out;
  for (Index i = 0; i < ps_.n_owned(); ++i)
    for (Index k = pairs_.first[i]; k < pairs_.first[i + 1]; ++k)
      out.push_back({ps_.id[i], ps_.id[pairs_.partner[k]]});
  return out;
}

void Level::prepare() {
  if (!law_prepared_) {
    const std::vector<Interaction> table = interaction_table();
    std::visit([&](auto& law) { law.prepare(materials_, table); }, law_);
    for (Wall& w : walls_) w.law_material = w.material < 0 ? materials_.rigid_index() : w.material;
    const int stride = history_size(law_);
    pairs_.history_stride = stride;
    wall_contacts_.history_stride = stride;
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
  std::vector<GlobalId>& keys = scratch_keys_;
  keys.resize(pairs_.size());
  for (std::size_t k = 0; k < keys.size(); ++k) keys[k] = ps_.id[pairs_.partner[k]];
  pair_carry_.save(pairs_, keys);
  keys.assign(wall_contacts_.partner.begin(), wall_contacts_.partner.end());
  wall_carry_.save(wall_contacts_, keys);
  origin_.resize(ps_.n_owned());
  for (Index i = 0; i < ps_.n_owned(); ++i) origin_[i] = i;
  pairs_.partner.clear();
  wall_contacts_.partner.clear();
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
  ghosts_.clear();
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
  const Real cutoff = 2 * r_max + skin_;
  const Real size_ratio = r_max / r_min;
  if (comm_.parallel()) {
    // Balanced slabs keep a margin over the cut-off: it grows when larger particles arrive.
    const Real min_width = 1.25 * cutoff;
    if (balance_every_ > 0 && step_ - balanced_at_step_ >= balance_every_) {
      const std::vector<Real> work = particle_work();
      if (imbalance(work) > balance_threshold_) balance_cuts(min_width, work);
      balanced_at_step_ = step_;
    }
    // A cut-off grown past a balanced slab's width: move the cuts (the same on every rank).
    if (!(decomposition_.narrowest_slab() >= cutoff)) balance_cuts(min_width, particle_work());
    const Real narrowest = decomposition_.narrowest_slab();
    if (!(narrowest >= cutoff)) {
      std::ostringstream c;
      c << "such that every subdomain is at least the ghost cut-off 2 r_max + skin = "
        << shortest(cutoff) << " m wide (use fewer ranks along the narrow axis); narrowest slab";
      throw_invalid("Simulation.processor_grid", c.str(), narrowest);
    }
    migrate(ps_, origin_, pair_carry_, wall_carry_, domain_, decomposition_, comm_);
  }

  // Spatial sort (owned particles in cell order, for cache locality in the force loop).
  grid_.build_for_pairs(ps_.position.data(), ps_.n_owned(), cutoff, size_ratio);
  std::vector<Index>& order = scratch_order_;
  order.assign(grid_.particles.begin(), grid_.particles.end());
  ps_.select_owned(order);
  std::vector<Index>& new_origin = scratch_index_;
  new_origin.resize(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) new_origin[k] = origin_[order[k]];
  origin_.swap(new_origin);

  ghosts_.build(ps_, domain_, decomposition_, comm_, cutoff);
  // Without ghosts the sorted particles fill the same cells in order: the grid only needs
  // renumbering, not a second binning.
  if (ps_.n_ghost() == 0)
    grid_.renumber_sorted();
  else
    grid_.build_for_pairs(ps_.position.data(), ps_.n_local(), cutoff, size_ratio);
  build_pair_list(ps_, grid_, cutoff, skin_, pairs_);
  // Mesh bins: once for a wall at rest, again after it moved or the reach grew.
  const Real margin = r_max + skin_;
  for (std::size_t w = 0; w < walls_.size(); ++w) {
    if (walls_[w].shape != WallShape::Mesh) continue;
    if (!mesh_bins_valid_[w] || w >= wall_shift_.size() || wall_shift_[w] > 0 ||
        margin > mesh_bin_margin_)
      walls_[w].mesh->build_bins(margin, cutoff);
    mesh_bins_valid_[w] = 1;
  }
  mesh_bin_margin_ = std::max(mesh_bin_margin_, margin);
  build_wall_list(ps_, walls_, primitives_.first, skin_, wall_contacts_);

  std::vector<GlobalId>& keys = scratch_keys_;
  keys.resize(pairs_.size());
  for (std::size_t k = 0; k < keys.size(); ++k) keys[k] = ps_.id[pairs_.partner[k]];
  pair_carry_.restore(origin_, keys, pairs_);
  keys.assign(wall_contacts_.partner.begin(), wall_contacts_.partner.end());
  wall_carry_.restore(origin_, keys, wall_contacts_);
  pair_carry_.clear();
  wall_carry_.clear();

  x_at_build_.assign(ps_.position.data(), ps_.position.data() + ps_.n_owned());
  drift_bound_ = 0;
  wall_shift_.assign(walls_.size(), 0);
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
  for (Wall& w : walls_) {
    w.force.setZero();
    w.torque.setZero();
  }
  for (const CouplingForces& c : couplings_) c.apply(ps_, domain_, dt_, coupling_push_scale(c));
  if constexpr (kStats) stats_.clear();
  accumulate_pair_forces<Law, kUpdate, kStats>(law, ps_, pairs_, dt_, stats_);
  // The ghost forces travel while the walls are computed (and, deferred, while the particles
  // that did not send ghosts are integrated); walls act on owned particles only.
  ghosts_.reverse_begin(ps_, comm_);
  accumulate_wall_forces<Law, kUpdate, kStats>(law, ps_, walls_, primitives_, wall_contacts_, dt_,
                                               stats_);
  if (defer_reverse && !ghosts_.deferred().empty()) {
    reverse_pending_ = true;
  } else {
    const ScopedTimer timer(halo_seconds_);
    ghosts_.reverse_end(ps_, comm_);
  }
  if (comm_.parallel()) {
    const ScopedTimer timer(halo_seconds_);
    // Servo walls move by the total load every step; other loads are read after a run.
    if (kStats || any_servo_) reduce_wall_loads();
    if constexpr (kStats) reduce_stats();
  }
}

template <bool kPlanar, class Law>
void Level::run_with(const Law& law, std::int64_t steps, bool stats) {
  // Ranks agree first: one rank's particles changed from Python means every rank rebuilds.
  // A set-up evaluation with valid lists first refreshes the ghosts: their velocities are those
  // of the last force evaluation, not of the closing kick or of changes made from Python.
  if (comm_.any(!lists_valid_))
    rebuild();
  else if (comm_.any(!forces_valid_))
    ghosts_.forward(ps_, comm_);
  if (comm_.any(!forces_valid_)) compute_forces<Law, false, true, false>(law);
  forces_valid_ = true;
  const Real half_skin = 0.5 * skin_;
  for (std::int64_t s = 0; s < steps; ++s) {
    // The previous step's closing half kick is fused into this pass (velocity_verlet.hpp),
    // which also resets the owned forces to m g.
    Real max_v2;
    if (reverse_pending_) {
      // The particles whose forces are complete move first, the others once theirs arrived.
      max_v2 = kick_drift_except<kPlanar>(ps_, dt_, gravity_, ghosts_.deferred_mask());
      {
        const ScopedTimer timer(halo_seconds_);
        ghosts_.reverse_end(ps_, comm_);
      }
      reverse_pending_ = false;
      max_v2 =
          larger_or_nan(max_v2, kick_drift_only<kPlanar>(ps_, dt_, gravity_, ghosts_.deferred()));
    } else {
      max_v2 = s == 0 ? kick_drift<kPlanar, false>(ps_, dt_, gravity_)
                      : kick_drift<kPlanar, true>(ps_, dt_, gravity_);
    }
    Real wall_shift = 0;
    for (std::size_t k = 0; k < walls_.size(); ++k) {
      wall_shift_[k] += walls_[k].advance(dt_, wall_reach_[k]);
      wall_shift = std::max(wall_shift, wall_shift_[k]);
    }
    ++step_;
    time_ = time_at_dt_change_ + (step_ - step_at_dt_change_) * dt_;
    apply_insertions_and_outlets();  // may add/remove particles: lists become invalid
    // Inserted particles start with zero force: then the owned forces are set again.
    const bool owned_reset = lists_valid_;
    // One reduction decides for all ranks (a rank that inserted or removed particles counts as
    // having moved infinitely far; NaN becomes infinity too). The list is rebuilt when a
    // particle has moved more than half the skin since the last build: the drift speeds bound
    // the displacements, and only when the bound reaches half the skin are they measured (the
    // same decisions as measuring every step, without reading the build positions each step).
    Real speed2_all;
    {
      const ScopedTimer timer(halo_seconds_);
      speed2_all = comm_.max(lists_valid_ ? max_v2 : INFINITY);
    }
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
      ghosts_.forward(ps_, comm_);
    }
    // Only a step followed by another in this run leaves its ghost forces travelling.
    const bool last = s + 1 == steps;
    if (last && stats)
      compute_forces<Law, true, true, false>(law);
    else if (owned_reset)
      compute_forces<Law, true, false, true>(law, !last);
    else
      compute_forces<Law, true, false, false>(law, !last);
  }
  // The wall loads are read after a run: summed over the ranks at the last step in any case.
  if (steps > 0 && !stats && comm_.parallel() && !any_servo_) {
    const ScopedTimer timer(halo_seconds_);
    reduce_wall_loads();
  }
  if (steps > 0) kick<kPlanar>(ps_, dt_);
}

void Level::run(std::int64_t steps, bool stats) {
  if (steps < 0) throw_invalid("Simulation.run.steps", "non-negative", steps);
  prepare();
  std::visit(
      [&](const auto& law) {
        if (dimension_ == 2)
          run_with<true>(law, steps, stats);
        else
          run_with<false>(law, steps, stats);
      },
      law_);
}

}  // namespace grainscale
