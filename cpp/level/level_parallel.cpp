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
    if (inside(i)) order.push_back(i);
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

Real Level::imbalance(const std::vector<std::int64_t>& counts) const {
  std::int64_t total = 0, most = 0;
  for (std::int64_t c : counts) {
    total += c;
    most = std::max(most, c);
  }
  if (total == 0) return 1;
  return static_cast<Real>(most) * static_cast<Real>(counts.size()) / static_cast<Real>(total);
}

void Level::balance_cuts(Real min_width) {
  for (int a = 0; a < 3; ++a) {
    const int n = decomposition_.grid[a];
    if (n == 1) continue;
    const Real lo = domain_.lo[a], hi = domain_.hi[a];
    // Histogram of the centres along the axis, 256 bins per slab, summed over the ranks.
    std::vector<std::int64_t> counts(256 * static_cast<std::size_t>(n), 0);
    const Real scale = static_cast<Real>(counts.size()) / (hi - lo);
    for (Index i = 0; i < ps_.n_owned(); ++i) {
      Real x = ps_.position[i][a];
      if (domain_.periodic[a]) x -= (hi - lo) * std::floor((x - lo) / (hi - lo));
      const auto b = static_cast<std::int64_t>(std::floor((x - lo) * scale));
      ++counts[std::clamp<std::int64_t>(b, 0, static_cast<std::int64_t>(counts.size()) - 1)];
    }
    comm_.sum_in_place(counts);
    decomposition_.cuts[a] = balanced_cuts(counts, lo, hi, n, min_width);
  }
}

std::pair<Real, Real> Level::balance() {
  ensure_decomposition();
  const Real before = imbalance(rank_counts());
  if (!comm_.parallel()) return {before, before};
  Real r_max = 0;
  for (Index i = 0; i < ps_.n_owned(); ++i) r_max = std::max(r_max, ps_.radius[i]);
  const Real cutoff = 2 * comm_.max(r_max) + skin_;
  if (lists_valid_) save_histories();
  lists_valid_ = false;  // the particles move to their new ranks at the next list build
  ps_.clear_ghosts();
  ghosts_.clear();
  balance_cuts(cutoff);
  balanced_at_step_ = step_;
  std::vector<std::int64_t> after(comm_.size(), 0);
  for (Index i = 0; i < ps_.n_owned(); ++i) ++after[decomposition_.owner(ps_.position[i], domain_)];
  comm_.sum_in_place(after);
  return {before, imbalance(after)};
}

void Level::set_auto_balance(std::int64_t every, Real threshold) {
  if (every < 0) throw_invalid("Simulation.balance.every", "a non-negative step count", every);
  if (!(threshold >= 1) || !std::isfinite(threshold))
    throw_invalid("Simulation.balance.threshold", ">= 1 (largest rank count / mean)", threshold);
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
