// Partition: processor grid, load balancing, migration at list builds and the gathering of
// nearby particles for insertion (DESIGN.md 5).
#include "level/partition.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <string>

#include "core/errors.hpp"
#include "level/migration.hpp"

namespace grainscale {

void Partition::set_processor_grid(const std::array<int, 3>& grid, const Communicator& comm,
                                   int dimension, bool particles) {
  for (int a = 0; a < 3; ++a)
    if (grid[a] < 1) throw_invalid("Simulation.processor_grid", "positive on every axis", grid[a]);
  if (grid[0] * grid[1] * grid[2] != comm.size()) {
    std::ostringstream v;
    v << "(" << grid[0] << ", " << grid[1] << ", " << grid[2] << ")";
    throw_invalid("Simulation.processor_grid",
                  "a grid of " + std::to_string(comm.size()) + " ranks (px py pz = ranks)",
                  v.str());
  }
  if (dimension == 2 && grid[2] != 1)
    throw_invalid("Simulation.processor_grid", "1 along z in the 2-D mode", grid[2]);
  if (particles)
    throw_invalid("Simulation.processor_grid", "set before particles are added", "particles");
  requested_grid_ = grid;
  decomposed_ = false;
}

void Partition::decompose(const Domain& domain, const Communicator& comm, int dimension) {
  const std::array<int, 3> grid =
      requested_grid_[0] > 0 ? requested_grid_
                             : choose_processor_grid(domain.length(), comm.size(), dimension);
  decomposition_ = Decomposition::uniform(domain, grid, comm.rank());
  decomposed_ = true;
}

void Partition::restore(const std::array<int, 3>& grid, const std::vector<Real>& cuts,
                        const Domain& domain, const Communicator& comm) {
  requested_grid_ = grid;
  decomposition_ = Decomposition::uniform(domain, requested_grid_, comm.rank());
  for (int a = 0, k = 0; a < 3; ++a)
    for (int c = 0; c <= requested_grid_[a]; ++c) decomposition_.cuts[a][c] = cuts[k++];
  decomposed_ = true;
}

std::vector<std::int64_t> Partition::rank_counts(const ParticleStore& ps,
                                                 const Communicator& comm) {
  const std::int64_t mine = ps.n_owned();
  std::vector<char> bytes(sizeof mine);
  std::memcpy(bytes.data(), &mine, sizeof mine);
  const std::vector<char> all = comm.allgather(bytes, nullptr);
  std::vector<std::int64_t> counts(all.size() / sizeof mine);
  std::memcpy(counts.data(), all.data(), all.size());
  return counts;
}

std::vector<Real> Partition::particle_work(const ParticleStore& ps, const ContactState& contacts) {
  // Per step a particle costs its integration, wall loop and list upkeep (1, about 40 ns on the
  // development VM), a distance test per list entry it stores (0.8: a cache miss for the
  // partner's data) and a force evaluation per touching contact (2), as timed per rank on the
  // 200k 'settle' case (bench/SCALING.md).
  std::vector<Real> work(ps.n_owned(), 1);
  auto entries = [](const ContactList& list, Index row) -> Real {
    return row >= 0 && static_cast<std::size_t>(row) + 1 < list.first.size()
               ? list.first[row + 1] - list.first[row]
               : 0;
  };
  const std::vector<Index>& origin = contacts.origin;
  for (Index i = 0; i < ps.n_owned(); ++i) {
    const Index row = i < static_cast<Index>(origin.size()) ? origin[i] : -1;
    work[i] += 0.8 * (entries(contacts.pairs, row) + entries(contacts.walls, row)) +
               2.0 * (contacts.pair_carry.row_size(row) + contacts.wall_carry.row_size(row));
  }
  return work;
}

Real Partition::imbalance(const std::vector<Real>& work, const Communicator& comm) {
  Real mine = 0;
  for (Real w : work) mine += w;
  std::vector<char> bytes(sizeof mine);
  std::memcpy(bytes.data(), &mine, sizeof mine);
  const std::vector<char> all = comm.allgather(bytes, nullptr);
  std::vector<Real> totals(all.size() / sizeof mine);
  std::memcpy(totals.data(), all.data(), all.size());
  Real total = 0, most = 0;
  for (Real t : totals) {
    total += t;
    most = std::max(most, t);
  }
  if (!(total > 0)) return 1;
  return most * static_cast<Real>(totals.size()) / total;
}

void Partition::balance_cuts(Real min_width, const std::vector<Real>& work, const ParticleStore& ps,
                             const Domain& domain, const Communicator& comm) {
  for (int a = 0; a < 3; ++a) {
    const int n = decomposition_.grid[a];
    if (n == 1) continue;
    const Real lo = domain.lo[a], hi = domain.hi[a];
    // Histogram of the work along the axis, 256 bins per slab, summed over the ranks.
    std::vector<Real> weights(256 * static_cast<std::size_t>(n), 0);
    const Real scale = static_cast<Real>(weights.size()) / (hi - lo);
    for (Index i = 0; i < ps.n_owned(); ++i) {
      Real x = ps.position[i][a];
      if (domain.periodic[a]) x -= (hi - lo) * std::floor((x - lo) / (hi - lo));
      const auto b = static_cast<std::int64_t>(std::floor((x - lo) * scale));
      weights[std::clamp<std::int64_t>(b, 0, static_cast<std::int64_t>(weights.size()) - 1)] +=
          work[i];
    }
    comm.sum_in_place(weights);
    decomposition_.cuts[a] = balanced_cuts(weights, lo, hi, n, min_width);
  }
}

void Partition::redistribute(std::int64_t step, Real cutoff, ParticleStore& ps,
                             ContactState& contacts, const Domain& domain,
                             const Communicator& comm) {
  // Balanced slabs keep a margin over the cut-off: it grows when larger particles arrive.
  const Real min_width = 1.25 * cutoff;
  if (balance_every_ > 0 && step - balanced_at_step_ >= balance_every_) {
    const std::vector<Real> work = particle_work(ps, contacts);
    if (imbalance(work, comm) > balance_threshold_) balance_cuts(min_width, work, ps, domain, comm);
    balanced_at_step_ = step;
  }
  // A cut-off grown past a balanced slab's width: move the cuts (the same on every rank).
  if (!(decomposition_.narrowest_slab() >= cutoff))
    balance_cuts(min_width, particle_work(ps, contacts), ps, domain, comm);
  const Real narrowest = decomposition_.narrowest_slab();
  if (!(narrowest >= cutoff)) {
    std::ostringstream c;
    c << "such that every subdomain is at least the ghost cut-off 2 r_max + skin = "
      << shortest(cutoff) << " m wide (use fewer ranks along the narrow axis); narrowest slab";
    throw_invalid("Simulation.processor_grid", c.str(), narrowest);
  }
  migrate(ps, contacts.origin, contacts.pair_carry, contacts.wall_carry, domain, decomposition_,
          comm);
}

std::pair<Real, Real> Partition::balance(std::int64_t step, Real skin, const ParticleStore& ps,
                                         const ContactState& contacts, const Domain& domain,
                                         const Communicator& comm) {
  const std::vector<Real> work = particle_work(ps, contacts);
  const Real before = imbalance(work, comm);
  Real r_max = 0;
  for (Index i = 0; i < ps.n_owned(); ++i) r_max = std::max(r_max, ps.radius[i]);
  const Real cutoff = 2 * comm.max(r_max) + skin;
  balance_cuts(1.25 * cutoff, work, ps, domain, comm);  // the margin of redistribute()
  balanced_at_step_ = step;
  std::vector<Real> after(comm.size(), 0);
  for (Index i = 0; i < ps.n_owned(); ++i)
    after[decomposition_.owner(ps.position[i], domain)] += work[i];
  comm.sum_in_place(after);
  Real total = 0, most = 0;
  for (Real t : after) {
    total += t;
    most = std::max(most, t);
  }
  return {before, total > 0 ? most * comm.size() / total : 1};
}

void Partition::set_auto_balance(std::int64_t every, Real threshold, std::int64_t step) {
  if (every < 0) throw_invalid("Simulation.balance.every", "a non-negative step count", every);
  if (!(threshold >= 1) || !std::isfinite(threshold))
    throw_invalid("Simulation.balance.threshold", ">= 1 (largest rank's work / mean)", threshold);
  balance_every_ = every;
  balance_threshold_ = threshold;
  balanced_at_step_ = step;
}

SphereSet Partition::gather_nearby(const Vec3& lo, const Vec3& hi, Real max_new_radius, Real& r_old,
                                   const ParticleStore& ps, const Domain& domain,
                                   const Communicator& comm) const {
  Real r_local = 0;
  for (Index i = 0; i < ps.n_owned(); ++i) r_local = std::max(r_local, ps.radius[i]);
  r_old = comm.max(r_local);
  SphereSet mine;
  OccupancyGrid::collect_nearby(lo, hi, max_new_radius, r_old, ps, domain, mine);
  if (!comm.parallel()) return mine;
  std::vector<char> bytes(mine.x.size() * 4 * sizeof(Real));
  Real* p = reinterpret_cast<Real*>(bytes.data());
  for (std::size_t k = 0; k < mine.x.size(); ++k, p += 4) {
    p[0] = mine.x[k][0];
    p[1] = mine.x[k][1];
    p[2] = mine.x[k][2];
    p[3] = mine.r[k];
  }
  const std::vector<char> all = comm.allgather(bytes, nullptr);
  SphereSet out;
  const std::size_t n = all.size() / (4 * sizeof(Real));
  std::vector<Real> values(4 * n);
  if (n > 0) std::memcpy(values.data(), all.data(), all.size());
  for (std::size_t k = 0; k < n; ++k) {
    out.x.emplace_back(values[4 * k], values[4 * k + 1], values[4 * k + 2]);
    out.r.push_back(values[4 * k + 3]);
  }
  return out;
}

}  // namespace grainscale
