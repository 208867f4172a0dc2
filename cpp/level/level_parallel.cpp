// Level: domain decomposition, load balancing and the reductions of a parallel run (DESIGN.md 5).
// Ghosts and migration themselves are in parallel/; this file decides where particles belong and
// sums what every rank contributes.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

#include "core/errors.hpp"
#include "level/level.hpp"

namespace grainscale {

void Level::set_processor_grid(const std::array<int, 3>& grid) {
  for (int a = 0; a < 3; ++a)
    if (grid[a] < 1) throw_invalid("Simulation.processor_grid", "positive on every axis", grid[a]);
  if (grid[0] * grid[1] * grid[2] != comm_.size()) {
    std::ostringstream v;
    v << "(" << grid[0] << ", " << grid[1] << ", " << grid[2] << ")";
    throw_invalid("Simulation.processor_grid",
                  "a grid of " + std::to_string(comm_.size()) + " ranks (px py pz = ranks)",
                  v.str());
  }
  if (dimension_ == 2 && grid[2] != 1)
    throw_invalid("Simulation.processor_grid", "1 along z in the 2-D mode", grid[2]);
  if (next_id_ > 0)
    throw_invalid("Simulation.processor_grid", "set before particles are added", "particles");
  requested_grid_ = grid;
  decomposed_ = false;
}

void Level::ensure_decomposition() {
  if (decomposed_) return;
  const std::array<int, 3> grid =
      requested_grid_[0] > 0 ? requested_grid_
                             : choose_processor_grid(domain_.length(), comm_.size(), dimension_);
  decomposition_ = Decomposition::uniform(domain_, grid, comm_.rank());
  decomposed_ = true;
}

const Decomposition& Level::decomposition() {
  ensure_decomposition();
  return decomposition_;
}

void Level::drop_lost() {
  const Index n = ps_.n_owned();
  auto inside = [&](Index i) {
    for (int a = 0; a < 3; ++a)
      if (!domain_.periodic[a] && !domain_.inside(ps_.position[i], a)) return false;
    return true;
  };
  Index kept = 0;
  for (Index i = 0; i < n; ++i) kept += inside(i);
  if (kept == n) return;
  std::vector<Index> order;
  order.reserve(kept);
  for (Index i = 0; i < n; ++i)
    if (inside(i)) {
      order.push_back(i);
    } else {
      lost_mass_ += ps_.mass[i];
      lost_log_.push_back(ps_.id[i]);
    }
  lost_ += n - kept;
  ps_.select_owned(order);
  std::vector<Index> new_origin(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) new_origin[k] = origin_[order[k]];
  origin_.swap(new_origin);
}

std::vector<std::int64_t> Level::rank_counts() const {
  const std::int64_t mine = ps_.n_owned();
  std::vector<char> bytes(sizeof mine);
  std::memcpy(bytes.data(), &mine, sizeof mine);
  const std::vector<char> all = comm_.allgather(bytes, nullptr);
  std::vector<std::int64_t> counts(all.size() / sizeof mine);
  std::memcpy(counts.data(), all.data(), all.size());
  return counts;
}

std::vector<Real> Level::particle_work() const {
  // Per step a particle costs its integration, wall loop and list upkeep (1, about 40 ns on the
  // development VM), a distance test per list entry it stores (0.8: a cache miss for the
  // partner's data) and a force evaluation per touching contact (2), as timed per rank on the
  // 200k 'settle' case (bench/SCALING.md).
  std::vector<Real> work(ps_.n_owned(), 1);
  auto entries = [](const ContactList& list, Index row) -> Real {
    return row >= 0 && static_cast<std::size_t>(row) + 1 < list.first.size()
               ? list.first[row + 1] - list.first[row]
               : 0;
  };
  for (Index i = 0; i < ps_.n_owned(); ++i) {
    const Index row = i < static_cast<Index>(origin_.size()) ? origin_[i] : -1;
    work[i] += 0.8 * (entries(pairs_, row) + entries(wall_contacts_, row)) +
               2.0 * (pair_carry_.row_size(row) + wall_carry_.row_size(row));
  }
  return work;
}

Real Level::imbalance(const std::vector<Real>& work) const {
  Real mine = 0;
  for (Real w : work) mine += w;
  std::vector<char> bytes(sizeof mine);
  std::memcpy(bytes.data(), &mine, sizeof mine);
  const std::vector<char> all = comm_.allgather(bytes, nullptr);
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

void Level::balance_cuts(Real min_width, const std::vector<Real>& work) {
  for (int a = 0; a < 3; ++a) {
    const int n = decomposition_.grid[a];
    if (n == 1) continue;
    const Real lo = domain_.lo[a], hi = domain_.hi[a];
    // Histogram of the work along the axis, 256 bins per slab, summed over the ranks.
    std::vector<Real> weights(256 * static_cast<std::size_t>(n), 0);
    const Real scale = static_cast<Real>(weights.size()) / (hi - lo);
    for (Index i = 0; i < ps_.n_owned(); ++i) {
      Real x = ps_.position[i][a];
      if (domain_.periodic[a]) x -= (hi - lo) * std::floor((x - lo) / (hi - lo));
      const auto b = static_cast<std::int64_t>(std::floor((x - lo) * scale));
      weights[std::clamp<std::int64_t>(b, 0, static_cast<std::int64_t>(weights.size()) - 1)] +=
          work[i];
    }
    comm_.sum_in_place(weights);
    decomposition_.cuts[a] = balanced_cuts(weights, lo, hi, n, min_width);
  }
}

std::pair<Real, Real> Level::balance() {
  ensure_decomposition();
  if (!comm_.parallel()) return {1, 1};
  if (lists_valid_) save_histories();
  lists_valid_ = false;  // the particles move to their new ranks at the next list build
  ps_.clear_ghosts();
  ghosts_.clear();
  const std::vector<Real> work = particle_work();
  const Real before = imbalance(work);
  Real r_max = 0;
  for (Index i = 0; i < ps_.n_owned(); ++i) r_max = std::max(r_max, ps_.radius[i]);
  const Real cutoff = 2 * comm_.max(r_max) + skin_;
  balance_cuts(1.25 * cutoff, work);  // the margin of rebuild()
  balanced_at_step_ = step_;
  std::vector<Real> after(comm_.size(), 0);
  for (Index i = 0; i < ps_.n_owned(); ++i)
    after[decomposition_.owner(ps_.position[i], domain_)] += work[i];
  comm_.sum_in_place(after);
  Real total = 0, most = 0;
  for (Real t : after) {
    total += t;
    most = std::max(most, t);
  }
  return {before, total > 0 ? most * comm_.size() / total : 1};
}

void Level::set_auto_balance(std::int64_t every, Real threshold) {
  if (every < 0) throw_invalid("Simulation.balance.every", "a non-negative step count", every);
  if (!(threshold >= 1) || !std::isfinite(threshold))
    throw_invalid("Simulation.balance.threshold", ">= 1 (largest rank's work / mean)", threshold);
  balance_every_ = every;
  balance_threshold_ = threshold;
  balanced_at_step_ = step_;
}

SphereSet Level::gather_nearby(const Vec3& lo, const Vec3& hi, Real max_new_radius,
                               Real& r_old) const {
  Real r_local = 0;
  for (Index i = 0; i < ps_.n_owned(); ++i) r_local = std::max(r_local, ps_.radius[i]);
  r_old = comm_.max(r_local);
  SphereSet mine;
  OccupancyGrid::collect_nearby(lo, hi, max_new_radius, r_old, ps_, domain_, mine);
  if (!comm_.parallel()) return mine;
  std::vector<char> bytes(mine.x.size() * 4 * sizeof(Real));
  Real* p = reinterpret_cast<Real*>(bytes.data());
  for (std::size_t k = 0; k < mine.x.size(); ++k, p += 4) {
    p[0] = mine.x[k][0];
    p[1] = mine.x[k][1];
    p[2] = mine.x[k][2];
    p[3] = mine.r[k];
  }
  const std::vector<char> all = comm_.allgather(bytes, nullptr);
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

void Level::reduce_wall_loads() {
  if (walls_.empty()) return;
  std::vector<Real> loads(6 * walls_.size());
  for (std::size_t w = 0; w < walls_.size(); ++w)
    for (int c = 0; c < 3; ++c) {
      loads[6 * w + c] = walls_[w].force[c];
      loads[6 * w + 3 + c] = walls_[w].torque[c];
    }
  comm_.sum_in_place(loads);
  for (std::size_t w = 0; w < walls_.size(); ++w)
    for (int c = 0; c < 3; ++c) {
      walls_[w].force[c] = loads[6 * w + c];
      walls_[w].torque[c] = loads[6 * w + 3 + c];
    }
}

void Level::reduce_stats() {
  stats_.contacts = comm_.sum(stats_.contacts);
  stats_.max_overlap_ratio = comm_.max(stats_.max_overlap_ratio);
}

}  // namespace grainscale
