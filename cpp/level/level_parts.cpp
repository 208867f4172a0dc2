// Level: the calls it hands to its owners (walls, partition, insertion, force hooks) with what
// they change in the level's own state (lists and forces to refresh), and particle deletion.
#include <algorithm>
#include <unordered_set>

#include "core/errors.hpp"
#include "level/level.hpp"

namespace grainscale {

int Level::add_wall(const Wall& wall) {
  Real reach = 0;
  const Wall w = WallSet::validated(wall, domain_, materials_.n_materials(), reach);
  if (lists_valid_) save_histories();
  const int index = walls_.add(w, reach);
  lists_valid_ = false;
  forces_valid_ = false;
  return index;
}

void Level::set_wall_motion(int index, const Vec3& velocity, const Vec3& angular_velocity,
                            const Vec3& origin) {
  walls_.set_motion(index, velocity, angular_velocity, origin);
  forces_valid_ = false;
}

void Level::set_wall_servo(int index, const Servo& servo) { walls_.set_servo(index, servo); }

void Level::set_processor_grid(const std::array<int, 3>& grid) {
  partition_.set_processor_grid(grid, comm_, dimension_, next_id_ > 0);
}

const Decomposition& Level::decomposition() {
  ensure_decomposition();
  return partition_.decomposition();
}

std::pair<Real, Real> Level::balance() {
  ensure_decomposition();
  if (!comm_.parallel()) return {1, 1};
  if (lists_valid_) save_histories();
  lists_valid_ = false;  // the particles move to their new ranks at the next list build
  ps_.clear_ghosts();
  ghosts().clear();
  return partition_.balance(step_, skin_, ps_, contacts_, domain_, comm_);
}

void Level::set_auto_balance(std::int64_t every, Real threshold) {
  partition_.set_auto_balance(every, threshold, step_);
}

std::vector<std::int64_t> Level::rank_counts() const { return Partition::rank_counts(ps_, comm_); }

void Level::reduce_stats() {
  stats_.contacts = comm_.sum(stats_.contacts);
  stats_.max_overlap_ratio = comm_.max(stats_.max_overlap_ratio);
}

std::pair<GlobalId, Index> Level::pack(const PackSpec& spec) {
  return insertion_.pack(*this, spec);
}

int Level::add_stream(const StreamSpec& spec) { return insertion_.add_stream(*this, spec); }

int Level::add_outlet(const OutletSpec& spec) { return insertion_.add_outlet(spec, time_); }

int Level::add_region_outlet(const OutletSpec& spec, std::shared_ptr<const ExchangeGrid> keep,
                             Real band) {
  return insertion_.add_outlet(spec, time_, OutletKeep{std::move(keep), band});
}

int Level::add_force_hook(std::shared_ptr<ForceHook> hook) {
  force_hooks_.push_back(std::move(hook));
  forces_valid_ = false;
  return static_cast<int>(force_hooks_.size()) - 1;
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
  std::vector<Index>& origin = contacts_.origin;
  std::vector<Index> new_origin(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) new_origin[k] = origin[order[k]];
  origin.swap(new_origin);
}

void Level::remove_owned(const std::vector<Index>& indices) {
  const Index n = ps_.n_owned();
  std::vector<char> drop(n, 0);
  for (Index i : indices) {
    if (i < 0 || i >= n) throw_invalid("remove_owned.index", "an owned particle index", i);
    drop[i] = 1;
  }
  if (indices.empty()) return;
  // As in add_particles/rebuild: histories are keyed by global ids while the lists are valid,
  // and the origin maps each survivor to the index it had then, so rebuild() restores them.
  if (lists_valid_) save_histories();
  lists_valid_ = false;
  ps_.clear_ghosts();
  ghosts().clear();
  std::vector<Index> order;
  order.reserve(n);
  for (Index i = 0; i < n; ++i)
    if (!drop[i]) order.push_back(i);
  ps_.select_owned(order);
  std::vector<Index>& origin = contacts_.origin;
  std::vector<Index> new_origin(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) new_origin[k] = origin[order[k]];
  origin.swap(new_origin);
}

std::int64_t Level::remove_particles(const std::vector<GlobalId>& ids) {
  const std::unordered_set<GlobalId> wanted(ids.begin(), ids.end());
  std::vector<Index> indices;
  for (Index i = 0; i < ps_.n_owned(); ++i)
    if (wanted.count(ps_.id[i])) indices.push_back(i);
  // The stored forces stay exact unless a removed particle touched a survivor (forces are then
  // re-evaluated before the next step). Every pair is stored on one rank, and every rank knows
  // all removed ids, so the ranks' verdicts combine to the serial one. Unknown contacts (lists
  // invalid): re-evaluate.
  const ContactList& pairs = contacts_.pairs;
  bool touched = !lists_valid_ && !indices.empty();
  for (Index i = 0; lists_valid_ && i < ps_.n_owned() && !touched; ++i) {
    const bool gone = wanted.count(ps_.id[i]) > 0;
    for (Index k = pairs.first[i]; k < pairs.first[i + 1]; ++k)
      if (pairs.touching[k] && gone != (wanted.count(ps_.id[pairs.partner[k]]) > 0)) touched = true;
  }
  remove_owned(indices);
  if (comm_.any(touched)) forces_valid_ = false;
  return comm_.sum(static_cast<std::int64_t>(indices.size()));
}

}  // namespace grainscale
