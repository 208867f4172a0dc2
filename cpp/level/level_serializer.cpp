// LevelSerializer: checkpoint state (save / load / load_redistributed / signature) over the
// level's parts. Saving first completes any pending list rebuild and set-up force evaluation —
// exactly what the next run() would do first — so the saved state is the one a continuing run
// steps from.
#include "level/level_serializer.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "core/errors.hpp"
#include "level/level.hpp"
#include "level/state_io.hpp"
#include "state/body_shape.hpp"

namespace grainscale {

namespace {

using state_io::get;
using state_io::ints;
using state_io::put;
using state_io::put_ints;
using state_io::reals;

// The rank's lost mass (kg); 0 in checkpoints written before it was kept.
Real saved_lost_mass(const LevelState& s) {
  auto it = s.reals.find("counters/lost_mass");
  if (it == s.reals.end()) return 0;
  if (it->second.size() != 1) throw std::runtime_error("checkpoint lost mass is corrupt");
  return it->second[0];
}

void put_list(LevelState& s, const std::string& key, const ContactList& l) {
  put_ints(s, key + "/first", l.first.data(), l.first.size());
  put_ints(s, key + "/partner", l.partner.data(), l.partner.size());
  put_ints(s, key + "/touching", l.touching.data(), l.touching.size());
  s.reals[key + "/history"].assign(l.history.begin(), l.history.end());
}

void get_list(const LevelState& s, const std::string& key, ContactList& l) {
  const auto& first = ints(s, key + "/first");
  const auto& partner = ints(s, key + "/partner");
  const auto& touching = ints(s, key + "/touching");
  l.first.assign(first.begin(), first.end());
  l.partner.assign(partner.begin(), partner.end());
  l.touching.assign(touching.begin(), touching.end());
  const auto& history = reals(s, key + "/history");
  l.history.assign(history.begin(), history.end());
  if (l.touching.size() != l.partner.size() ||
      l.history.size() != l.partner.size() * static_cast<std::size_t>(l.history_stride))
    throw std::runtime_error("checkpoint contact list '" + key +
                             "' does not match this contact law's history size");
  index_rows(l);
}

// A saved contact list for `rows` owned particles: offsets from 0, non-decreasing, ending at
// the entry count; partners in [0, partners); touching 0 or 1; `stride` history values per
// entry.
void check_list(const LevelState& s, const std::string& key, std::size_t rows, std::size_t partners,
                int stride) {
  const auto& first = ints(s, key + "/first");
  const auto& partner = ints(s, key + "/partner");
  const auto& touching = ints(s, key + "/touching");
  const auto bad = [&](const std::string& what) {
    throw std::runtime_error("checkpoint contact list '" + key + "' is damaged: " + what);
  };
  if (first.size() != rows + 1) bad("its offsets do not match the particle count");
  if (first[0] != 0 || first.back() != static_cast<std::int64_t>(partner.size()))
    bad("its offsets do not span its entries");
  for (std::size_t k = 0; k < rows; ++k)
    if (first[k + 1] < first[k]) bad("its offsets decrease");
  for (auto p : partner)
    if (p < 0 || static_cast<std::size_t>(p) >= partners) bad("a partner is out of range");
  if (touching.size() != partner.size()) bad("touching flags and entries differ in number");
  for (auto t : touching)
    if (t != 0 && t != 1) bad("a touching flag is neither 0 nor 1");
  if (reals(s, key + "/history").size() != partner.size() * static_cast<std::size_t>(stride))
    bad("its history does not match this contact law's history size");
}

// Ghost stages: per stage axis, dir, send_to, recv_from, recv_first, recv_count, n_send, then
// the sent indices; the shifts separately.
void put_ghost_stages(LevelState& s, const std::vector<GhostStage>& stages) {
  auto& ints = s.ints["ghosts/stages"];
  auto& shifts = s.reals["ghosts/shifts"];
  ints.clear();
  shifts.clear();
  for (const GhostStage& g : stages) {
    ints.insert(ints.end(), {g.axis, g.dir, g.send_to, g.recv_from, g.recv_first, g.recv_count,
                             static_cast<std::int64_t>(g.send.size())});
    ints.insert(ints.end(), g.send.begin(), g.send.end());
    shifts.insert(shifts.end(), {g.shift[0], g.shift[1], g.shift[2]});
  }
}

std::vector<GhostStage> get_ghost_stages(const LevelState& s, std::size_t n_owned,
                                         std::size_t n_local) {
  const auto& in = ints(s, "ghosts/stages");
  const auto& shifts = reals(s, "ghosts/shifts");
  std::vector<GhostStage> stages;
  std::size_t k = 0;
  std::size_t next_slot = n_owned;
  while (k < in.size()) {
    if (in.size() - k < 7) throw std::runtime_error("checkpoint ghost stages are corrupt");
    GhostStage g;
    g.axis = static_cast<int>(in[k]);
    g.dir = static_cast<int>(in[k + 1]);
    g.send_to = static_cast<int>(in[k + 2]);
    g.recv_from = static_cast<int>(in[k + 3]);
    g.recv_first = static_cast<Index>(in[k + 4]);
    g.recv_count = static_cast<Index>(in[k + 5]);
    const std::size_t n_send = static_cast<std::size_t>(in[k + 6]);
    k += 7;
    if (in.size() - k < n_send || g.axis < 0 || g.axis > 2 ||
        static_cast<std::size_t>(g.recv_first) != next_slot || g.recv_count < 0)
      throw std::runtime_error("checkpoint ghost stages are corrupt");
    next_slot += g.recv_count;
    for (std::size_t j = 0; j < n_send; ++j, ++k) {
      if (in[k] < 0 || static_cast<std::size_t>(in[k]) >= n_local)
        throw std::runtime_error("checkpoint ghost stage refers to a missing particle");
      g.send.push_back(static_cast<Index>(in[k]));
    }
    const std::size_t t = stages.size();
    if (shifts.size() < 3 * (t + 1))
      throw std::runtime_error("checkpoint ghost shifts are corrupt");
    g.shift = Vec3(shifts[3 * t], shifts[3 * t + 1], shifts[3 * t + 2]);
    stages.push_back(std::move(g));
  }
  if (next_slot != n_local) throw std::runtime_error("checkpoint ghost stages are corrupt");
  return stages;
}

// The decomposition a state was saved under: ranks, grid, this rank, the cut positions and the
// automatic balancing schedule (every, threshold, last balanced step). The schedule's keys are
// not under "decomposition/": ints "decomposition" is a dataset of the HDF5 file, not a group.
void put_decomposition(LevelState& s, const Partition& p, int ranks) {
  const Decomposition& d = p.decomposition();
  s.ints["decomposition"] = {ranks, d.grid[0], d.grid[1], d.grid[2], d.rank};
  auto& cuts = s.reals["decomposition/cuts"];
  cuts.clear();
  for (int a = 0; a < 3; ++a) cuts.insert(cuts.end(), d.cuts[a].begin(), d.cuts[a].end());
  const Partition::BalanceSchedule b = p.balance_schedule();
  s.ints["balance_schedule"] = {b.every, b.balanced_at_step};
  s.reals["balance_threshold"] = {b.threshold};
}

// The saved balancing schedule, if the checkpoint holds one (written before it was saved: none).
std::optional<Partition::BalanceSchedule> saved_balance_schedule(const LevelState& s) {
  const auto ib = s.ints.find("balance_schedule");
  const auto rb = s.reals.find("balance_threshold");
  if (ib == s.ints.end() && rb == s.reals.end()) return std::nullopt;
  if (ib == s.ints.end() || rb == s.reals.end() || ib->second.size() != 2 ||
      rb->second.size() != 1 || ib->second[0] < 0 || ib->second[1] < 0 || !(rb->second[0] >= 1) ||
      !std::isfinite(rb->second[0]))
    throw std::runtime_error("checkpoint load-balancing schedule is corrupt");
  return Partition::BalanceSchedule{ib->second[0], rb->second[0], ib->second[1]};
}

}  // namespace

std::string LevelSerializer::signature(const Level& l) {
  return signature(l, l.materials_.n_materials());
}

std::string LevelSerializer::signature(const Level& l, int n_materials) {
  std::ostringstream s;
  s << "law=" << law_name(l.law_) << ";materials=" << n_materials << ";walls=" << l.walls_.size()
    << ";primitives=" << l.walls_.primitives().wall.size()
    << ";streams=" << l.insertion_.streams().size() << ";outlets=" << l.insertion_.outlets().size()
    << ";periodic=" << l.domain_.periodic[0] << l.domain_.periodic[1] << l.domain_.periodic[2];
  // Only the 2-D mode is named, so 3-D checkpoints written before it existed still load.
  if (l.dimension_ != 3) s << ";dimension=" << l.dimension_;
  return s.str();
}

LevelState LevelSerializer::save(Level& l) {
  l.prepare();
  l.refresh_forces();

  LevelState s;
  s.texts["signature"] = signature(l);
  const std::size_t nl = l.ps_.n_local(), no = l.ps_.n_owned();
  s.ints["scalars"] = {l.step_,     l.step_at_dt_change_,          l.next_id_,       l.lost_,
                       l.rebuilds_, static_cast<std::int64_t>(no), l.stats_.contacts};
  s.reals["scalars"] = {l.time_, l.time_at_dt_change_,       l.dt_,
                        l.skin_, l.walls_.mesh_bin_margin(), l.stats_.max_overlap_ratio};
  s.reals["counters/lost_mass"] = {l.lost_mass_};
  put(s, "particles/position", l.ps_.position.data(), nl);
  put(s, "particles/velocity", l.ps_.velocity.data(), nl);
  put(s, "particles/angular_velocity", l.ps_.angular_velocity.data(), nl);
  put(s, "particles/force", l.ps_.force.data(), nl);
  put(s, "particles/torque", l.ps_.torque.data(), nl);
  s.reals["particles/radius"].assign(l.ps_.radius.data(), l.ps_.radius.data() + nl);
  s.reals["particles/mass"].assign(l.ps_.mass.data(), l.ps_.mass.data() + nl);
  s.reals["particles/inv_mass"].assign(l.ps_.inv_mass.data(), l.ps_.inv_mass.data() + nl);
  s.reals["particles/inv_inertia"].assign(l.ps_.inv_inertia.data(), l.ps_.inv_inertia.data() + nl);
  s.reals["particles/inv_rolling_inertia"].assign(l.ps_.inv_rolling_inertia.data(),
                                                  l.ps_.inv_rolling_inertia.data() + nl);
  put_ints(s, "particles/material", l.ps_.material.data(), nl);
  put_ints(s, "particles/id", l.ps_.id.data(), nl);
  put_ghost_stages(s, l.ghosts().stages());
  put_decomposition(s, l.partition_, l.comm_.size());
  put(s, "lists/x_at_build", l.x_at_build_.data(), l.x_at_build_.size());
  put_list(s, "lists/pairs", l.contacts_.pairs);
  put_list(s, "lists/walls", l.contacts_.walls);
  l.walls_.save_state(s);
  l.insertion_.save_state(s);
  return s;
}

namespace {

// The particle arrays of a saved state (owned [0, no), then ghosts), checked for consistency.
struct SavedParticles {
  std::size_t no = 0, nl = 0;
  std::vector<Vec3> x, v, w, f, t;
  const std::vector<double>*radius, *mass, *inv_mass, *inv_inertia, *inv_rolling;
  const std::vector<std::int64_t>*material, *id;

  SavedParticles(const LevelState& s, int n_materials) {
    nl = reals(s, "particles/radius").size();
    no = static_cast<std::size_t>(ints(s, "scalars").at(5));
    if (no > nl) throw std::runtime_error("checkpoint particle counts are corrupt");
    radius = &reals(s, "particles/radius");
    mass = &reals(s, "particles/mass");
    inv_mass = &reals(s, "particles/inv_mass");
    inv_inertia = &reals(s, "particles/inv_inertia");
    inv_rolling = &reals(s, "particles/inv_rolling_inertia");
    material = &ints(s, "particles/material");
    id = &ints(s, "particles/id");
    if (mass->size() != nl || inv_mass->size() != nl || inv_inertia->size() != nl ||
        inv_rolling->size() != nl || material->size() != nl || id->size() != nl)
      throw std::runtime_error("checkpoint particle arrays have different lengths");
    for (std::size_t k = 0; k < nl; ++k)
      if ((*material)[k] < 0 || (*material)[k] >= n_materials)
        throw std::runtime_error("checkpoint particle material index out of range");
    for (auto* a : {&x, &v, &w, &f, &t}) a->resize(nl);
    get(s, "particles/position", x.data(), nl);
    get(s, "particles/velocity", v.data(), nl);
    get(s, "particles/angular_velocity", w.data(), nl);
    get(s, "particles/force", f.data(), nl);
    get(s, "particles/torque", t.data(), nl);
  }

  // Every particle's values: radius, mass and the inverses positive and finite, the inverses
  // those ParticleStore::add_owned derives from the mass and radius (to round-off), position,
  // velocity and spin finite. Throws naming the array, the particle's id and the value.
  void check_values(int dimension) const {
    for (std::size_t k = 0; k < nl; ++k) {
      const Real r = (*radius)[k], m = (*mass)[k];
      positive(k, "particles/radius", r, " (m)");
      positive(k, "particles/mass", m, " (kg)");
      const Real inertia = particle_inertia(m, r, dimension);
      derived(k, "particles/inv_mass", (*inv_mass)[k], m, "1 / mass (1/kg)", "mass");
      derived(k, "particles/inv_inertia", (*inv_inertia)[k], inertia,
              "1 / moment of inertia (1/(kg m^2))", "mass and radius");
      derived(k, "particles/inv_rolling_inertia", (*inv_rolling)[k], inertia + m * r * r,
              "1 / (I + m r^2) (1/(kg m^2))", "mass and radius");
      finite(k, "particles/position", x[k], " (m)");
      finite(k, "particles/velocity", v[k], " (m/s)");
      finite(k, "particles/angular_velocity", w[k], " (rad/s)");
    }
  }

  // Owned particles lie inside the domain along its closed axes, to within `skin`: they may
  // have moved up to half the skin since the last list build, which kept only those inside
  // (periodic axes are wrapped at that build: their positions are not checked).
  void check_inside(const Domain& domain, Real skin) const {
    for (std::size_t k = 0; k < no; ++k)
      for (int a = 0; a < 3; ++a)
        if (!domain.periodic[a] &&
            !(x[k][a] >= domain.lo[a] - skin && x[k][a] <= domain.hi[a] + skin)) {
          std::ostringstream c;
          c << "positions inside the domain [" << shortest(domain.lo[a]) << ", "
            << shortest(domain.hi[a]) << "] m along the closed axis " << "xyz"[a]
            << " (to within the skin, " << shortest(skin) << " m)";
          fail("particles/position", c.str(), x[k][a], k);
        }
  }

  [[noreturn]] void fail(const std::string& array, const std::string& constraint, Real value,
                         std::size_t k, const std::string& note = "") const {
    std::ostringstream m;
    m << "checkpoint array '" << array << "' must hold " << constraint << ", got "
      << shortest(value) << " for the particle with id " << (*id)[k] << note;
    throw std::runtime_error(m.str());
  }

  void positive(std::size_t k, const std::string& array, Real value, const char* unit) const {
    if (!(value > 0 && std::isfinite(value)))
      fail(array, std::string("positive, finite values") + unit, value, k);
  }

  void finite(std::size_t k, const std::string& array, const Vec3& value, const char* unit) const {
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(value[c]))
        fail(array, std::string("finite values") + unit, value[c], k,
             std::string(" (component ") + "xyz"[c] + ")");
  }

  // `value` must be 1 / `of` to round-off (1e-9 relative: a genuine state holds exactly what
  // add_owned computed).
  void derived(std::size_t k, const std::string& array, Real value, Real of, const char* what,
               const char* from) const {
    if (!(value > 0 && std::isfinite(value) && std::abs(value * of - 1) <= 1e-9))
      fail(array, what, value, k,
           std::string(" (from its saved ") + from + ": " + shortest(1 / of) + ")");
  }

  // Appends saved particle k to `ps` as an owned particle with its saved bits (add_owned would
  // derive 1/m and 1/I anew).
  void add_owned_to(ParticleStore& ps, std::size_t k) const {
    ps.add_owned((*id)[k], x[k], v[k], w[k], (*radius)[k], (*mass)[k], 1 / (*inv_inertia)[k],
                 static_cast<std::int32_t>((*material)[k]));
    const Index i = ps.n_owned() - 1;
    ps.inv_mass[i] = (*inv_mass)[k];
    ps.inv_inertia[i] = (*inv_inertia)[k];
    ps.inv_rolling_inertia[i] = (*inv_rolling)[k];
    ps.force[i] = f[k];
    ps.torque[i] = t[k];
  }
};

}  // namespace

namespace {

// The time step and the skin a restart continues with: positive and finite.
void check_scalars(const LevelState& s) {
  const auto& sr = reals(s, "scalars");
  const char* names[] = {"time step (s)", "skin (m)"};
  for (int k = 0; k < 2; ++k)
    if (!(sr[2 + k] > 0 && std::isfinite(sr[2 + k])))
      throw std::runtime_error(std::string("checkpoint scalar '") + names[k] +
                               "' must be positive and finite, got " + shortest(sr[2 + k]));
}

}  // namespace

void LevelSerializer::check_signature(const Level& l, const LevelState& s, int n_materials) {
  auto sig = s.texts.find("signature");
  if (sig == s.texts.end()) throw std::runtime_error("checkpoint lacks its set-up signature");
  const std::string here = signature(l, n_materials);
  if (sig->second != here)
    throw InvalidArgument("checkpoint was written for the set-up '" + sig->second +
                          "', this simulation is '" + here + "'");
  const auto& si = ints(s, "scalars");
  const auto& sr = reals(s, "scalars");
  if (si.size() != 7 || sr.size() != 6) throw std::runtime_error("checkpoint scalars are corrupt");
  const auto& dec = ints(s, "decomposition");
  const auto& cuts = reals(s, "decomposition/cuts");
  if (dec.size() != 5 || dec[1] < 1 || dec[2] < 1 || dec[3] < 1 ||
      cuts.size() != static_cast<std::size_t>(dec[1] + dec[2] + dec[3] + 3))
    throw std::runtime_error("checkpoint decomposition is corrupt");
}

// Scalars shared by every rank's state (step, time, ids, time step, skin, statistics); `lost`
// and `lost_mass` are the rank's own.
void LevelSerializer::load_scalars(Level& l, const LevelState& s, std::int64_t lost,
                                   Real lost_mass) {
  const auto& si = ints(s, "scalars");
  const auto& sr = reals(s, "scalars");
  l.step_ = si[0];
  l.step_at_dt_change_ = si[1];
  l.next_id_ = si[2];
  l.lost_ = lost;
  l.lost_mass_ = lost_mass;
  l.rebuilds_ = si[4];
  l.stats_.contacts = si[6];
  l.time_ = sr[0];
  l.time_at_dt_change_ = sr[1];
  l.dt_ = sr[2];
  l.skin_ = sr[3];
  l.walls_.set_mesh_bin_margin(sr[4]);
  l.stats_.max_overlap_ratio = sr[5];
}

void LevelSerializer::validate(const Level& l, const LevelState& s, bool exact, int n_materials) {
  check_signature(l, s, n_materials);
  const SavedParticles saved(s, n_materials);
  const std::size_t no = saved.no, nl = saved.nl;
  const std::int64_t next_id = ints(s, "scalars")[2];
  std::vector<std::int64_t> ids(saved.id->begin(), saved.id->begin() + no);
  std::sort(ids.begin(), ids.end());
  if (!ids.empty() && (ids.front() < 0 || ids.back() >= next_id))
    throw std::runtime_error("checkpoint particle ids are out of range");
  if (std::adjacent_find(ids.begin(), ids.end()) != ids.end())
    throw std::runtime_error("checkpoint holds two particles with one id");
  check_scalars(s);
  saved_balance_schedule(s);
  saved.check_values(l.dimension_);
  saved.check_inside(l.domain_, reals(s, "scalars")[3]);
  const int stride = history_size(l.law_);
  check_list(s, "lists/pairs", no, nl, stride);
  check_list(s, "lists/walls", no, l.walls_.primitives().wall.size(), stride);
  if (exact) {
    get_ghost_stages(s, no, nl);
    if (reals(s, "lists/x_at_build").size() != 3 * no)
      throw std::runtime_error("checkpoint array 'lists/x_at_build' has the wrong size");
  }
  l.walls_.check_state(s);
  l.insertion_.check_state(s);
}

void LevelSerializer::load(Level& l, const LevelState& s) {
  validate(l, s, true, l.materials_.n_materials());
  const auto& dec = ints(s, "decomposition");
  const auto& cuts = reals(s, "decomposition/cuts");
  if (dec[0] != l.comm_.size() || dec[4] != l.comm_.rank())
    throw InvalidArgument("checkpoint state of rank " + std::to_string(dec[4]) + " of " +
                          std::to_string(dec[0]) + " cannot be loaded exactly on rank " +
                          std::to_string(l.comm_.rank()) + " of " + std::to_string(l.comm_.size()) +
                          " (load_redistributed takes any rank count)");
  l.partition_.restore(
      {static_cast<int>(dec[1]), static_cast<int>(dec[2]), static_cast<int>(dec[3])}, cuts,
      l.domain_, l.comm_);
  if (const auto b = saved_balance_schedule(s)) l.partition_.restore_balance_schedule(*b);
  const auto& sr = reals(s, "scalars");
  l.dt_ = sr[2];
  l.skin_ = sr[3];
  l.prepare();  // law tables and history layout of this set-up
  const SavedParticles saved(s, l.materials_.n_materials());
  const std::size_t no = saved.no, nl = saved.nl;

  l.ps_.clear_ghosts();
  ParticleStore fresh;
  fresh.reserve(static_cast<Index>(nl));
  for (std::size_t k = 0; k < no; ++k) saved.add_owned_to(fresh, k);
  std::vector<GhostStage> stages = get_ghost_stages(s, no, nl);
  fresh.add_ghost_slots(static_cast<Index>(nl - no));
  for (std::size_t k = no; k < nl; ++k) {
    fresh.position[k] = saved.x[k];
    fresh.velocity[k] = saved.v[k];
    fresh.angular_velocity[k] = saved.w[k];
    fresh.force[k] = saved.f[k];
    fresh.torque[k] = saved.t[k];
    fresh.radius[k] = (*saved.radius)[k];
    fresh.mass[k] = (*saved.mass)[k];
    fresh.inv_mass[k] = (*saved.inv_mass)[k];
    fresh.inv_inertia[k] = (*saved.inv_inertia)[k];
    fresh.inv_rolling_inertia[k] = (*saved.inv_rolling)[k];
    fresh.material[k] = static_cast<std::int32_t>((*saved.material)[k]);
    fresh.id[k] = (*saved.id)[k];
  }
  l.ps_ = std::move(fresh);
  l.ghosts().set_stages(std::move(stages), static_cast<Index>(no), l.comm_);

  l.x_at_build_.resize(no);
  get(s, "lists/x_at_build", l.x_at_build_.data(), no);
  l.drift_bound_ = INFINITY;  // not saved: the first step measures the displacements exactly
  ContactState& contacts = l.contacts_;
  get_list(s, "lists/pairs", contacts.pairs);
  get_list(s, "lists/walls", contacts.walls);
  for (auto p : contacts.pairs.partner)
    if (p < 0 || static_cast<std::size_t>(p) >= nl)
      throw std::runtime_error("checkpoint pair list refers to a missing particle");
  if (contacts.pairs.first.size() != no + 1 || contacts.walls.first.size() != no + 1)
    throw std::runtime_error("checkpoint contact lists do not match the particle count");

  l.walls_.load_state(s);
  load_scalars(l, s, ints(s, "scalars")[3], saved_lost_mass(s));
  l.insertion_.load_state(s);
  contacts.origin.assign(no, -1);
  contacts.pair_carry = HistoryCarry();
  contacts.wall_carry = HistoryCarry();
  l.lists_valid_ = true;
  l.forces_valid_ = true;
}

void LevelSerializer::load_redistributed(Level& l, const std::vector<LevelState>& states) {
  if (states.empty()) throw std::runtime_error("checkpoint holds no rank state");
  for (const LevelState& s : states) validate(l, s, false, l.materials_.n_materials());
  const LevelState& first = states.front();
  if (static_cast<std::size_t>(ints(first, "decomposition")[0]) != states.size())
    throw std::runtime_error("checkpoint holds " + std::to_string(states.size()) +
                             " rank states, written by " +
                             std::to_string(ints(first, "decomposition")[0]) + " ranks");
  const auto& sr = reals(first, "scalars");
  l.dt_ = sr[2];
  l.skin_ = sr[3];
  l.prepare();  // law tables, history layout and this run's decomposition
  const int stride = history_size(l.law_);

  // Every saved owned particle that lies in this rank's subdomain, with the touching entries of
  // the pairs it stores (keyed by the partner's id) and of its wall contacts (primitive index).
  l.ps_.clear_ghosts();
  l.ghosts().clear();
  ParticleStore fresh;
  ContactState& contacts = l.contacts_;
  contacts.pair_carry.start(stride);
  contacts.wall_carry.start(stride);
  std::int64_t lost = 0;
  Real lost_mass = 0;
  for (const LevelState& s : states) {
    const SavedParticles saved(s, l.materials_.n_materials());
    ContactList pairs, walls;
    pairs.history_stride = walls.history_stride = stride;
    get_list(s, "lists/pairs", pairs);
    get_list(s, "lists/walls", walls);
    if (pairs.first.size() != saved.no + 1 || walls.first.size() != saved.no + 1)
      throw std::runtime_error("checkpoint contact lists do not match the particle count");
    std::vector<GlobalId> keys;
    std::vector<Real> values;
    auto carry = [&](const ContactList& list, std::size_t k, bool by_id, HistoryCarry& out) {
      keys.clear();
      values.clear();
      for (Index e = list.first[k]; e < list.first[k + 1]; ++e) {
        if (!list.touching[e]) continue;
        const Index p = list.partner[e];
        if (by_id && (p < 0 || static_cast<std::size_t>(p) >= saved.nl))
          throw std::runtime_error("checkpoint pair list refers to a missing particle");
        keys.push_back(by_id ? (*saved.id)[p] : p);
        values.insert(values.end(), list.history.begin() + static_cast<std::size_t>(e) * stride,
                      list.history.begin() + static_cast<std::size_t>(e + 1) * stride);
      }
      out.append_row(keys.data(), values.data(), static_cast<Index>(keys.size()));
    };
    for (std::size_t k = 0; k < saved.no; ++k) {
      if (!l.owns(saved.x[k])) continue;
      saved.add_owned_to(fresh, k);
      carry(pairs, k, true, contacts.pair_carry);
      carry(walls, k, false, contacts.wall_carry);
    }
    lost += ints(s, "scalars")[3];
    lost_mass += saved_lost_mass(s);
  }
  l.ps_ = std::move(fresh);
  contacts.origin.resize(l.ps_.n_owned());
  for (Index i = 0; i < l.ps_.n_owned(); ++i) contacts.origin[i] = i;
  contacts.pairs = ContactList();
  contacts.walls = ContactList();
  contacts.pairs.history_stride = contacts.walls.history_stride = stride;
  l.x_at_build_.clear();

  l.walls_.load_state(first);
  load_scalars(l, first, l.comm_.rank() == 0 ? lost : 0, l.comm_.rank() == 0 ? lost_mass : 0);
  l.insertion_.load_state(first);
  // The balancing schedule carries over between parallel runs; a serial checkpoint (never
  // balanced) leaves a parallel run its own, and a serial run does not balance.
  if (const auto b = saved_balance_schedule(first); b && ints(first, "decomposition")[0] > 1)
    l.partition_.restore_balance_schedule(*b);
  // The saved forces are complete (ghost shares folded in): the first step uses them; the lists
  // are built for this decomposition first, restoring the histories from the carries.
  l.lists_valid_ = false;
  l.forces_valid_ = true;
}

LevelState Level::save_state() { return LevelSerializer::save(*this); }
void Level::load_state(const LevelState& state) { LevelSerializer::load(*this, state); }
void Level::load_redistributed(const std::vector<LevelState>& states) {
  LevelSerializer::load_redistributed(*this, states);
}
std::string Level::signature() const { return LevelSerializer::signature(*this); }
void Level::check_state(const LevelState& state, bool exact, int n_materials) const {
  LevelSerializer::validate(*this, state, exact, n_materials);
}

}  // namespace grainscale
