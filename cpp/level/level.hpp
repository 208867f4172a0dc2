// Level: one complete DEM system — particles, neighbour lists with contact history, contact
// law, walls, ghost exchange and time step. A simulation is one level; an MLCG hierarchy holds
// several. Python decides what runs and when; run(steps) executes whole steps in C++.
//
// The level orders a step (level/level_step.cpp: kick and drift, walls, the insertion hook, list
// rebuild, forces) and holds the owners of its parts: the wall set (level/wall_set.hpp),
// insertion and outlets (level/insertion.hpp), the spread over the ranks (level/partition.hpp),
// the contact lists and carried histories (level/contact_state.hpp) and the forces that higher
// floors add every step (level/force_hook.hpp). Checkpoints are written and read by
// level/level_serializer.hpp.
//
// Under MPI a level is decomposed over the ranks of its Communicator: every rank runs the same
// calls (SPMD) with the same arguments, owns the particles of its subdomain and holds ghosts of
// its neighbours'. Set-up is replicated (materials, law, walls, inserters); insertion places the
// same particles on every rank and each keeps its own; results that Python reads (energies, wall
// loads, outlet masses, counts) are reduced over the ranks. Calls marked "collective" must be
// made on every rank.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "contact/contact_law.hpp"
#include "contact/contact_stats.hpp"
#include "geometry/wall.hpp"
#include "insert/centre_grid.hpp"
#include "level/contact_state.hpp"
#include "level/force_hook.hpp"
#include "level/guards.hpp"
#include "level/insertion.hpp"
#include "level/level_state.hpp"
#include "level/partition.hpp"
#include "level/wall_set.hpp"
#include "neighbor/cell_grid.hpp"
#include "parallel/communicator.hpp"
#include "parallel/decomposition.hpp"
#include "state/domain.hpp"
#include "state/material_table.hpp"
#include "state/particle_store.hpp"

namespace grainscale {

class Level {
 public:
  explicit Level(const Domain& domain, Communicator comm = Communicator());

  // --- configuration (validated; errors name the Python-visible parameter) ---
  int add_material(const MaterialProperties& props);
  const MaterialTable& materials() const { return materials_; }
  void set_contact_law(const ContactLaw& law);
  const ContactLaw& contact_law() const { return law_; }
  // Interaction properties of the pair of materials i, j (symmetric; index -1 = rigid wall).
  // Pairs never set use the default interaction.
  void set_interaction(int i, int j, const Interaction& interaction);
  void set_default_interaction(const Interaction& interaction);
  void set_gravity(const Vec3& g);
  const Vec3& gravity() const { return gravity_; }
  void set_time_step(Real dt, bool force);
  Real time_step() const { return dt_; }
  bool force_time_step() const { return force_dt_; }
  void set_skin(Real skin);
  Real skin() const { return skin_; }
  const Domain& domain() const { return domain_; }
  // 2 (discs in the plane z = plane_z(), the domain's mid-height) or 3 (spheres); set before
  // any particle exists (DESIGN.md 2.1, 2.2; integrate/velocity_verlet.hpp for what is frozen).
  void set_dimension(int dimension);
  int dimension() const { return dimension_; }
  Real plane_z() const { return 0.5 * (domain_.lo[2] + domain_.hi[2]); }

  // Adds n particles (arrays of 3n / n values; velocity and angular velocity may be null).
  // Returns the global id of the first one; the others follow consecutively. Under MPI every
  // rank passes all n and keeps those in its subdomain.
  GlobalId add_particles(Index n, const Real* position, const Real* velocity,
                         const Real* angular_velocity, const Real* radius,
                         const std::int32_t* material);
  // Places particles found room for at an insertion site, all with one velocity, spin (may be
  // null: none) and material (collective: every rank the same particles, each keeps its own);
  // returns the global id of the first. The placement primitive of packing, streams and the
  // hierarchy's flux insertion (coupling/flux_insertion.hpp).
  GlobalId place_particles(const std::vector<Vec3>& position, const std::vector<Real>& radius,
                           const Vec3& velocity, const Vec3* spin, std::int32_t material);
  // Collective: the occupancy of every rank's particles near the box [lo, hi] for new particles
  // of radius at most max_new_radius, and the clearance of the walls where they are now.
  InsertionSite insertion_site(const Vec3& lo, const Vec3& hi, Real max_new_radius) const;
  // Collective: the centres of every rank's particles within `reach` (m) of the box [lo, hi], in
  // a grid whose nearest() finds them up to that distance.
  CentreGrid centres_near(const Vec3& lo, const Vec3& hi, Real reach) const;
  // The global id the next particle added will get.
  GlobalId next_id() const { return next_id_; }

  // Validates and adds a wall (plane, rectangle, cylinder or triangle mesh); returns its index.
  int add_wall(const Wall& wall);
  std::vector<Wall>& walls() { return walls_.walls(); }
  const WallSet& wall_set() const { return walls_; }
  // Changes a wall's motion (translation, rotation about origin) or servo control.
  void set_wall_motion(int index, const Vec3& velocity, const Vec3& angular_velocity,
                       const Vec3& origin);
  void set_wall_servo(int index, const Servo& servo);

  // --- parallel runs (level/partition.hpp) ---
  const Communicator& comm() const { return comm_; }
  // Processor grid (px, py, pz) with px py pz = ranks; set before any particle exists.
  // Default: chosen from the box shape (choose_processor_grid).
  void set_processor_grid(const std::array<int, 3>& grid);
  const Decomposition& decomposition();
  // Collective. Moves the cuts so that the slabs hold equal shares of the work (particles move at
  // the next list build); returns the imbalance (largest rank's work / mean) before and after.
  // The work of a particle is 1 + 0.8 per list entry + 2 per touching contact (of those it
  // stores: each pair counts once), a deterministic estimate (level/partition.cpp), so balanced
  // runs stay reproducible.
  std::pair<Real, Real> balance();
  // Collective when set: at list builds at least `every` steps apart, balance() when the
  // imbalance exceeds `threshold`. every = 0 switches it off. Parallel runs start with
  // every = 500 steps and threshold 1.05.
  void set_auto_balance(std::int64_t every, Real threshold);
  // Collective: owned particles on every rank (in rank order), and their sum.
  std::vector<std::int64_t> rank_counts() const;
  std::int64_t global_count() const { return comm_.sum(static_cast<std::int64_t>(ps_.n_owned())); }
  // --- end parallel runs ---

  // --- running ---
  // Collective. stats: fill last_stats() (contact count, largest overlap, records) at the last
  // step; without, last_stats() keeps what an earlier run left (Simulation.run asks for them
  // only where a thermo line, an output or the caller reads them).
  void run(std::int64_t steps, bool stats = true);
  // Tells the level that Python changed positions (needs a rebuild) or velocities (forces
  // are recomputed, without advancing contact histories, before the next step).
  void mark_positions_changed();
  void mark_velocities_changed() { forces_valid_ = false; }

  // --- guards (level/guards.hpp, guards.cpp) ---
  // Collective when set. Off by default; every run() then stops (std::runtime_error on every
  // rank) at the end of a step in which a particle moved more than max_step_displacement x its
  // radius, at once on a non-finite position or velocity, and after its last step if a contact
  // overlaps more than max_overlap x the smaller radius. They only read: a run they do not stop
  // is bit-identical to one without them.
  void set_guards(const GuardLimits& limits);
  // Throws if a wall moves more than max_step_displacement x the smallest radius in one step.
  void check_wall_speeds() const;
  const GuardLimits& guards() const { return guards_; }
  // Whether a guard stopped the last run() (reset when the next one starts).
  bool guard_tripped() const { return guard_tripped_; }

  // --- checkpoint (level/level_serializer.cpp) ---
  // Everything needed to continue bit-identically; load_state needs the same set-up
  // (materials, law, walls, inserters), checked through signature().
  // Collective. save_state is this rank's part; load_state takes the part of the same rank
  // saved under the same number of ranks and continues bit-identically. load_redistributed
  // takes every rank's part of a checkpoint written on any number of ranks and keeps what lies
  // in this rank's subdomain (histories included); the continuation then differs from the
  // uninterrupted run only by round-off (the lists are rebuilt for the new decomposition).
  LevelState save_state();
  void load_state(const LevelState& state);
  void load_redistributed(const std::vector<LevelState>& states);
  // Every check of a load, changing nothing: throws std::runtime_error naming the damage.
  // exact: as load_state (else as one part of load_redistributed); n_materials: the materials
  // registered by the time of the load.
  void check_state(const LevelState& state, bool exact, int n_materials) const;
  std::string signature() const;

  // --- state and diagnostics ---
  ParticleStore& particles() { return ps_; }
  std::int64_t step() const { return step_; }
  Real time() const { return time_; }
  // Collective: particles that left through a closed side, over all ranks.
  std::int64_t lost_particles() const { return comm_.sum(lost_); }
  Real lost_mass() const { return comm_.sum(lost_mass_); }  // kg, collective
  // Global ids of this rank's particles lost since clear_lost_log() (a hierarchy's flux meter
  // tells losses from discharges with it; not checkpointed: cleared every exchange interval).
  const std::vector<GlobalId>& lost_log() const { return lost_log_; }
  void clear_lost_log() { lost_log_.clear(); }
  std::int64_t rebuilds() const { return rebuilds_; }
  // Wall-clock seconds spent in neighbour-list rebuilds (sorting, ghosts, lists, histories).
  double rebuild_seconds() const { return rebuild_seconds_; }
  // Wall-clock seconds spent in the per-step exchanges: ghost updates (forward and reverse) and
  // the reductions of a step (bench/SCALING.md compares them with the halo model).
  double halo_seconds() const { return halo_seconds_; }
  const ContactStats& last_stats() const { return stats_; }
  // Keep a record of every touching contact at the last step of each run() (diagnostics).
  void set_record_contacts(bool on) { stats_.record = on; }
  bool record_contacts() const { return stats_.record; }
  Real kinetic_energy() const;          // collective
  Real smallest_rayleigh_time() const;  // collective
  // Pairs (global ids) of this rank's current particle list, each unordered pair once.
  std::vector<std::array<GlobalId, 2>> neighbor_pairs() const;

  // --- insertion and outlets (level/insertion.hpp) ---
  // Packs particles into a region without overlaps, with each other and with the particles
  // present; returns the global id of the first and the count (ids are consecutive, largest
  // particle first). Throws std::runtime_error, inserting nothing, if the target is out of reach.
  std::pair<GlobalId, Index> pack(const PackSpec& spec);  // collective
  // Registers a stream inserter / an outlet; both run inside run() (the per-step hook), so the
  // result does not depend on how Python chunks run(). Returns the index.
  int add_stream(const StreamSpec& spec);
  int add_outlet(const OutletSpec& spec);
  // An outlet that removes the particles leaving `keep`'s region cells (insertion.hpp).
  int add_region_outlet(const OutletSpec& spec, std::shared_ptr<const ExchangeGrid> keep,
                        Real band);
  std::vector<StreamInserter>& streams() { return insertion_.streams(); }
  std::vector<Outlet>& outlets() { return insertion_.outlets(); }
  // Deletes owned particles by index (order irrelevant, repeats ignored) keeping the contact
  // histories of the survivors (the forces are then those of the step before: the per-step hook
  // recomputes them). remove_particles (collective) does it by global id, every rank given the
  // same ids, re-evaluates the forces before the next step if a removed particle touched a
  // survivor, and returns the number removed over all ranks.
  void remove_owned(const std::vector<Index>& indices);
  std::int64_t remove_particles(const std::vector<GlobalId>& ids);
  // Smallest Rayleigh time (s) of the particles the streams may insert (inf without streams).
  Real smallest_insertion_rayleigh_time() const {
    return insertion_.smallest_rayleigh_time(materials_);
  }
  // --- end insertion and outlets ---

  // --- forces added by higher floors (level/force_hook.hpp) ---
  // Applied at every force evaluation after the force reset, in the order added; returns the
  // index. The forces are re-evaluated before the next step.
  int add_force_hook(std::shared_ptr<ForceHook> hook);
  int force_hook_count() const { return static_cast<int>(force_hooks_.size()); }
  ForceHook& force_hook(int index) { return *force_hooks_.at(index); }

 private:
  friend class LevelSerializer;

  // Returns true if a step guard stopped the run early (after finishing that step).
  template <bool kPlanar, class Law>
  bool run_with(const Law& law, std::int64_t steps, bool stats);
  // Guards (guards.cpp): the smallest radius and speed bound at the start of a run; the rare
  // path that finds this rank's offender; the collective agreement, stopping at once for
  // non-finite values; the overlap check after a run; the collective throw with the remedy.
  void start_guards();
  void update_guard_limit();
  bool step_guard_hit();
  bool agree_step_guard(bool hit);
  std::string step_fallback() const;
  void check_overlap_guard();
  [[noreturn]] void raise_guard(const std::string& message, const std::string& fallback);
  // kOwnedReset: the owned forces already hold m g and the torques zero (set by kick_drift).
  template <class Law, bool kUpdate, bool kStats, bool kOwnedReset>
  // defer_reverse: leaves the ghost forces travelling (GhostExchange::reverse_begin); the next
  // step's kick completes them (reverse_pending_).
  void compute_forces(const Law& law, bool defer_reverse = false);
  // Collective: rebuilds the lists if needed and evaluates the forces (without advancing the
  // histories) if needed: what run() does first, and save_state before saving.
  void refresh_forces();
  void prepare();
  void validate_periodic_lengths() const;
  void ensure_decomposition() { partition_.ensure(domain_, comm_, dimension_); }
  bool owns(const Vec3& x) const { return partition_.owns(x, domain_, comm_); }
  GhostExchange& ghosts() { return partition_.ghosts(); }
  // Drops owned particles outside the closed sides of the box (counted as lost).
  void drop_lost();
  void reduce_stats();
  std::vector<Interaction> interaction_table() const;
  void save_histories();
  void rebuild();
  // Insertion and outlets: runs once per step after the drift; adding or removing particles
  // invalidates the lists, so the step rebuilds them.
  void apply_insertions_and_outlets();

  Domain domain_;
  MaterialTable materials_;
  ContactLaw law_;
  Interaction default_interaction_;
  std::map<std::pair<int, int>, Interaction> interactions_;
  Vec3 gravity_ = Vec3::Zero();
  Real dt_ = 0;
  bool force_dt_ = false;
  Real skin_ = 0;
  int dimension_ = 3;

  ParticleStore ps_;
  WallSet walls_;
  ContactState contacts_;  // lists, carried histories and each particle's row in them
  CellGrid grid_;
  Communicator comm_;
  Partition partition_;  // after comm_: initialised from it
  std::vector<Vec3> x_at_build_;
  // Upper bound of any owned particle's displacement from x_at_build_ (m): the drift speeds'
  // sum over the steps since the build, tightened to the exact maximum whenever it is checked.
  // Infinite until known (after a checkpoint load), so the first step checks exactly.
  Real drift_bound_ = INFINITY;
  // Rebuild scratch kept between rebuilds: fresh large buffers would cost page faults each time.
  std::vector<Index> scratch_order_, scratch_index_;
  ContactStats stats_;
  GuardLimits guards_;
  Real guard_r_min_ = INFINITY;   // smallest radius over the ranks (m), at the run's start / build
  Real guard_speed2_ = INFINITY;  // (max_step_displacement x guard_r_min_ / dt)^2
  std::string guard_message_;     // this rank's offender, if any
  bool guard_fatal_ = false;      // guard_message_ is about a non-finite value
  bool guard_tripped_ = false;

  GlobalId next_id_ = 0;
  std::int64_t step_ = 0;
  Real time_ = 0;
  Real time_at_dt_change_ = 0;
  std::int64_t step_at_dt_change_ = 0;
  std::int64_t lost_ = 0;
  Real lost_mass_ = 0;  // this rank's
  std::vector<GlobalId> lost_log_;
  std::int64_t rebuilds_ = 0;
  double rebuild_seconds_ = 0;
  double halo_seconds_ = 0;
  bool lists_valid_ = false;
  bool forces_valid_ = false;
  bool reverse_pending_ = false;  // ghost forces still travelling (compute_forces)
  bool law_prepared_ = false;

  Insertion insertion_;
  std::vector<std::shared_ptr<ForceHook>> force_hooks_;
};

}  // namespace grainscale
