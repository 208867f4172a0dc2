// Level: checkpoint state (save_state / load_state). Saving first completes any pending list
// rebuild and set-up force evaluation — exactly what the next run() would do first — so the
// saved state is the one a continuing run steps from.
#include <algorithm>
#include <sstream>

#include "core/errors.hpp"
#include "level/level.hpp"

namespace grainscale {

namespace {

void put(LevelState& s, const std::string& key, const Vec3* v, std::size_t n) {
  auto& out = s.reals[key];
  out.resize(3 * n);
  for (std::size_t k = 0; k < n; ++k)
    for (int c = 0; c < 3; ++c) out[3 * k + c] = v[k][c];
}

void get(const LevelState& s, const std::string& key, Vec3* v, std::size_t n) {
  const auto& in = s.reals.at(key);
  if (in.size() != 3 * n)
    throw std::runtime_error("checkpoint array '" + key + "' has the wrong size");
  for (std::size_t k = 0; k < n; ++k) v[k] = Vec3(in[3 * k], in[3 * k + 1], in[3 * k + 2]);
}

template <class T>
void put_ints(LevelState& s, const std::string& key, const T* v, std::size_t n) {
  s.ints[key].assign(v, v + n);
}

const std::vector<double>& reals(const LevelState& s, const std::string& key) {
  auto it = s.reals.find(key);
  if (it == s.reals.end()) throw std::runtime_error("checkpoint lacks '" + key + "'");
  return it->second;
}

const std::vector<std::int64_t>& ints(const LevelState& s, const std::string& key) {
  auto it = s.ints.find(key);
  if (it == s.ints.end()) throw std::runtime_error("checkpoint lacks '" + key + "'");
  return it->second;
}

void put_list(LevelState& s, const std::string& key, const ContactList& l) {
  put_ints(s, key + "/first", l.first.data(), l.first.size());
  put_ints(s, key + "/partner", l.partner.data(), l.partner.size());
  put_ints(s, key + "/touching", l.touching.data(), l.touching.size());
  s.reals[key + "/history"] = l.history;
}

void get_list(const LevelState& s, const std::string& key, ContactList& l) {
  const auto& first = ints(s, key + "/first");
  const auto& partner = ints(s, key + "/partner");
  const auto& touching = ints(s, key + "/touching");
  l.first.assign(first.begin(), first.end());
  l.partner.assign(partner.begin(), partner.end());
  l.touching.assign(touching.begin(), touching.end());
  l.history = reals(s, key + "/history");
  if (l.touching.size() != l.partner.size() ||
      l.history.size() != l.partner.size() * static_cast<std::size_t>(l.history_stride))
    throw std::runtime_error("checkpoint contact list '" + key +
                             "' does not match this contact law's history size");
}

}  // namespace

std::string Level::signature() const {
  std::ostringstream s;
  s << "law=" << law_name(law_) << ";materials=" << materials_.n_materials()
    << ";walls=" << walls_.size() << ";primitives=" << primitives_.wall.size()
    << ";streams=" << streams_.size() << ";outlets=" << outlets_.size()
    << ";periodic=" << domain_.periodic[0] << domain_.periodic[1] << domain_.periodic[2];
  // Only the 2-D mode is named, so 3-D checkpoints written before it existed still load.
  if (dimension_ != 3) s << ";dimension=" << dimension_;
  return s.str();
}

LevelState Level::save_state() {
  prepare();
  std::visit(
      [&](const auto& law) {
        if (!lists_valid_) rebuild();
        if (!forces_valid_) compute_forces<std::decay_t<decltype(law)>, false, true, false>(law);
      },
      law_);
  forces_valid_ = true;

  LevelState s;
  s.texts["signature"] = signature();
  const std::size_t nl = ps_.n_local(), no = ps_.n_owned();
  s.ints["scalars"] = {step_,          step_at_dt_change_, next_id_,
                       lost_,          rebuilds_,          static_cast<std::int64_t>(no),
                       stats_.contacts};
  s.reals["scalars"] = {time_, time_at_dt_change_, dt_,
                        skin_, mesh_bin_margin_,   stats_.max_overlap_ratio};
  put(s, "particles/position", ps_.position.data(), nl);
  put(s, "particles/velocity", ps_.velocity.data(), nl);
  put(s, "particles/angular_velocity", ps_.angular_velocity.data(), nl);
  put(s, "particles/force", ps_.force.data(), nl);
  put(s, "particles/torque", ps_.torque.data(), nl);
  s.reals["particles/radius"].assign(ps_.radius.data(), ps_.radius.data() + nl);
  s.reals["particles/mass"].assign(ps_.mass.data(), ps_.mass.data() + nl);
  s.reals["particles/inv_mass"].assign(ps_.inv_mass.data(), ps_.inv_mass.data() + nl);
  s.reals["particles/inv_inertia"].assign(ps_.inv_inertia.data(), ps_.inv_inertia.data() + nl);
  s.reals["particles/inv_rolling_inertia"].assign(ps_.inv_rolling_inertia.data(),
                                                  ps_.inv_rolling_inertia.data() + nl);
  put_ints(s, "particles/material", ps_.material.data(), nl);
  put_ints(s, "particles/id", ps_.id.data(), nl);
  put_ints(s, "ghosts/owner", ps_.ghost_owner.data(), ps_.ghost_owner.size());
  put(s, "ghosts/shift", ps_.ghost_shift.data(), ps_.ghost_shift.size());
  put(s, "lists/x_at_build", x_at_build_.data(), x_at_build_.size());
  put_list(s, "lists/pairs", pairs_);
  put_list(s, "lists/walls", wall_contacts_);
  s.reals["walls/shift"] = wall_shift_;
  for (std::size_t w = 0; w < walls_.size(); ++w) {
    const Wall& wall = walls_[w];
    const std::string key = "walls/" + std::to_string(w) + "/";
    const Vec3 geometry[] = {
        wall.point,          wall.normal,           wall.edge1,  wall.edge2, wall.axis,
        wall.velocity,       wall.angular_velocity, wall.origin, wall.force, wall.torque,
        wall.servo.direction};
    put(s, key + "vectors", geometry, std::size(geometry));
    s.reals[key + "servo"] = {wall.servo.enabled ? 1.0 : 0.0, wall.servo.target_force,
                              wall.servo.gain, wall.servo.max_speed};
    if (wall.mesh) put(s, key + "vertices", wall.mesh->vertices.data(), wall.mesh->vertices.size());
  }
  save_insertion_state(s);
  return s;
}

void Level::load_state(const LevelState& s) {
  auto sig = s.texts.find("signature");
  if (sig == s.texts.end()) throw std::runtime_error("checkpoint lacks its set-up signature");
  if (sig->second != signature())
    throw InvalidArgument("checkpoint was written for the set-up '" + sig->second +
                          "', this simulation is '" + signature() + "'");
  const auto& si = ints(s, "scalars");
  const auto& sr = reals(s, "scalars");
  if (si.size() != 7 || sr.size() != 6) throw std::runtime_error("checkpoint scalars are corrupt");
  dt_ = sr[2];
  skin_ = sr[3];
  prepare();  // law tables and history layout of this set-up
  const std::size_t nl = reals(s, "particles/radius").size();
  const std::size_t no = static_cast<std::size_t>(si[5]);
  if (no > nl) throw std::runtime_error("checkpoint particle counts are corrupt");

  ps_.clear_ghosts();
  ParticleStore fresh;
  fresh.reserve(static_cast<Index>(no));
  const auto& radius = reals(s, "particles/radius");
  const auto& mass = reals(s, "particles/mass");
  const auto& inv_mass = reals(s, "particles/inv_mass");
  const auto& inv_inertia = reals(s, "particles/inv_inertia");
  const auto& inv_rolling = reals(s, "particles/inv_rolling_inertia");
  const auto& material = ints(s, "particles/material");
  const auto& id = ints(s, "particles/id");
  if (mass.size() != nl || inv_mass.size() != nl || inv_inertia.size() != nl ||
      inv_rolling.size() != nl || material.size() != nl || id.size() != nl)
    throw std::runtime_error("checkpoint particle arrays have different lengths");
  std::vector<Vec3> x(nl), v(nl), w(nl), f(nl), t(nl);
  get(s, "particles/position", x.data(), nl);
  get(s, "particles/velocity", v.data(), nl);
  get(s, "particles/angular_velocity", w.data(), nl);
  get(s, "particles/force", f.data(), nl);
  get(s, "particles/torque", t.data(), nl);
  for (std::size_t k = 0; k < no; ++k) {
    if (material[k] < 0 || material[k] >= materials_.n_materials())
      throw std::runtime_error("checkpoint particle material index out of range");
    fresh.add_owned(id[k], x[k], v[k], w[k], radius[k], mass[k], 1 / inv_inertia[k],
                    static_cast<std::int32_t>(material[k]));
    // add_owned derives 1/m and 1/I; keep the saved bits.
    fresh.inv_mass[k] = inv_mass[k];
    fresh.inv_inertia[k] = inv_inertia[k];
    fresh.inv_rolling_inertia[k] = inv_rolling[k];
    fresh.force[k] = f[k];
    fresh.torque[k] = t[k];
  }
  const auto& owner = ints(s, "ghosts/owner");
  std::vector<Vec3> shift(owner.size());
  get(s, "ghosts/shift", shift.data(), shift.size());
  if (owner.size() != nl - no) throw std::runtime_error("checkpoint ghost arrays are corrupt");
  for (std::size_t g = 0; g < owner.size(); ++g) {
    if (owner[g] < 0 || static_cast<std::size_t>(owner[g]) >= no)
      throw std::runtime_error("checkpoint ghost owner out of range");
    fresh.add_ghost(static_cast<Index>(owner[g]), shift[g]);
    const std::size_t k = no + g;
    fresh.position[k] = x[k];
    fresh.force[k] = f[k];
    fresh.torque[k] = t[k];
  }
  ps_ = std::move(fresh);

  x_at_build_.resize(no);
  get(s, "lists/x_at_build", x_at_build_.data(), no);
  get_list(s, "lists/pairs", pairs_);
  get_list(s, "lists/walls", wall_contacts_);
  for (auto p : pairs_.partner)
    if (p < 0 || static_cast<std::size_t>(p) >= nl)
      throw std::runtime_error("checkpoint pair list refers to a missing particle");
  if (pairs_.first.size() != no + 1 || wall_contacts_.first.size() != no + 1)
    throw std::runtime_error("checkpoint contact lists do not match the particle count");

  wall_shift_ = reals(s, "walls/shift");
  if (wall_shift_.size() != walls_.size())
    throw std::runtime_error("checkpoint wall count differs");
  for (std::size_t k = 0; k < walls_.size(); ++k) {
    Wall& wall = walls_[k];
    const std::string key = "walls/" + std::to_string(k) + "/";
    Vec3 g[11];
    get(s, key + "vectors", g, 11);
    wall.point = g[0];
    wall.normal = g[1];
    wall.edge1 = g[2];
    wall.edge2 = g[3];
    wall.axis = g[4];
    wall.velocity = g[5];
    wall.angular_velocity = g[6];
    wall.origin = g[7];
    wall.force = g[8];
    wall.torque = g[9];
    wall.servo.direction = g[10];
    const auto& servo = reals(s, key + "servo");
    if (servo.size() != 4) throw std::runtime_error("checkpoint servo state is corrupt");
    wall.servo.enabled = servo[0] != 0;
    wall.servo.target_force = servo[1];
    wall.servo.gain = servo[2];
    wall.servo.max_speed = servo[3];
    if (wall.mesh) {
      // Own copy: the restarted mesh may not share vertices with the set-up's.
      wall.mesh = std::make_shared<TriangleMesh>(*wall.mesh);
      get(s, key + "vertices", wall.mesh->vertices.data(), wall.mesh->vertices.size());
      mesh_bins_valid_[k] = 0;  // rebuilt from these vertices at the next list build
    }
  }

  step_ = si[0];
  step_at_dt_change_ = si[1];
  next_id_ = si[2];
  lost_ = si[3];
  rebuilds_ = si[4];
  stats_.contacts = si[6];
  time_ = sr[0];
  time_at_dt_change_ = sr[1];
  dt_ = sr[2];
  skin_ = sr[3];
  mesh_bin_margin_ = sr[4];
  stats_.max_overlap_ratio = sr[5];
  load_insertion_state(s);
  origin_.assign(no, -1);
  pair_carry_ = HistoryCarry();
  wall_carry_ = HistoryCarry();
  lists_valid_ = true;
  forces_valid_ = true;
}

// save_insertion_state / load_insertion_state: level/level_insert.cpp

}  // namespace grainscale
