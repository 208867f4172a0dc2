// Partition: how a level is spread over the ranks of its Communicator (DESIGN.md 5) — the
// processor grid and cut positions, the ghost exchange, migration at list builds, load
// balancing from a deterministic estimate of each particle's work, and the gathering of every
// rank's particles near an insertion box. Ghosts and migration themselves are in
// parallel/ghost_exchange and level/migration; this class decides where particles belong.
#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "insert/occupancy_grid.hpp"
#include "level/contact_state.hpp"
#include "parallel/communicator.hpp"
#include "parallel/decomposition.hpp"
#include "parallel/ghost_exchange.hpp"
#include "state/domain.hpp"
#include "state/particle_store.hpp"

namespace grainscale {

class Partition {
 public:
  // Parallel runs start with automatic balancing every 500 steps.
  explicit Partition(bool parallel) : balance_every_(parallel ? 500 : 0) {}

  // Processor grid (px, py, pz), px py pz = ranks; `particles`: whether any exist yet (refused).
  void set_processor_grid(const std::array<int, 3>& grid, const Communicator& comm, int dimension,
                          bool particles);
  void ensure(const Domain& domain, const Communicator& comm, int dimension) {
    if (!decomposed_) decompose(domain, comm, dimension);
  }
  // The decomposition a checkpoint was saved under: grid and cut positions.
  void restore(const std::array<int, 3>& grid, const std::vector<Real>& cuts, const Domain& domain,
               const Communicator& comm);
  const Decomposition& decomposition() const { return decomposition_; }
  bool owns(const Vec3& x, const Domain& domain, const Communicator& comm) const {
    return decomposition_.owner(x, domain) == comm.rank();
  }
  GhostExchange& ghosts() { return ghosts_; }
  const GhostExchange& ghosts() const { return ghosts_; }

  void set_auto_balance(std::int64_t every, Real threshold, std::int64_t step);
  // The automatic balancing schedule, saved in checkpoints: a restart must rebalance at the
  // steps the continuing run would, or the two part ways in the last bits.
  struct BalanceSchedule {
    std::int64_t every;
    Real threshold;
    std::int64_t balanced_at_step;
  };
  BalanceSchedule balance_schedule() const {
    return {balance_every_, balance_threshold_, balanced_at_step_};
  }
  void restore_balance_schedule(const BalanceSchedule& s) {
    balance_every_ = s.every;
    balance_threshold_ = s.threshold;
    balanced_at_step_ = s.balanced_at_step;
  }
  // At a list build (parallel runs; lists invalid, histories saved, no ghosts): balances when
  // due, moves cuts a grown cut-off made too narrow, then migrates the particles with their
  // carried histories. Collective.
  void redistribute(std::int64_t step, Real cutoff, ParticleStore& ps, ContactState& contacts,
                    const Domain& domain, const Communicator& comm);
  // Level::balance after the level invalidated its lists: the imbalance before and after.
  std::pair<Real, Real> balance(std::int64_t step, Real skin, const ParticleStore& ps,
                                const ContactState& contacts, const Domain& domain,
                                const Communicator& comm);
  // Every rank's nearby spheres of an insertion box, on every rank (OccupancyGrid input).
  SphereSet gather_nearby(const Vec3& lo, const Vec3& hi, Real max_new_radius, Real& r_old,
                          const ParticleStore& ps, const Domain& domain,
                          const Communicator& comm) const;
  // Collective: owned particles on every rank (in rank order).
  static std::vector<std::int64_t> rank_counts(const ParticleStore& ps, const Communicator& comm);

 private:
  void decompose(const Domain& domain, const Communicator& comm, int dimension);
  // Work of every owned particle (see Level::balance), from the carried histories: requires
  // lists invalid (histories saved).
  static std::vector<Real> particle_work(const ParticleStore& ps, const ContactState& contacts);
  // Cut positions for equal work along every split axis, slabs at least `min_width` wide.
  void balance_cuts(Real min_width, const std::vector<Real>& work, const ParticleStore& ps,
                    const Domain& domain, const Communicator& comm);
  // Largest rank's total work / mean; collective.
  static Real imbalance(const std::vector<Real>& work, const Communicator& comm);

  GhostExchange ghosts_;
  Decomposition decomposition_;
  std::array<int, 3> requested_grid_{0, 0, 0};  // 0: choose from the box shape
  bool decomposed_ = false;
  std::int64_t balance_every_ = 0;
  Real balance_threshold_ = 1.05;
  std::int64_t balanced_at_step_ = 0;
};

}  // namespace grainscale
