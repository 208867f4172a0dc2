// WallSet: adding a wall with its checks, prescribed motion, servo control, mesh bins, the loads'
// reduction over the ranks and the walls' checkpoint part.
#include "level/wall_set.hpp"

#include <cmath>
#include <memory>
#include <string>

#include "core/errors.hpp"
#include "level/state_io.hpp"

namespace grainscale {

Wall WallSet::validated(const Wall& wall, const Domain& domain, int n_materials, Real& reach) {
  Wall w = wall;
  for (const Vec3* v : {&w.point, &w.velocity, &w.angular_velocity, &w.origin})
    if (!v->allFinite()) throw_invalid("Wall motion and position", "finite", v->transpose());
  auto unit = [](Vec3& v, const char* name) {
    const Real len = v.norm();
    if (!(len > 0) || !std::isfinite(len))
      throw_invalid(name, "a non-zero finite vector", v.transpose());
    v /= len;
  };
  reach = (domain.hi - domain.lo).norm() + (w.origin - 0.5 * (domain.lo + domain.hi)).norm();
  switch (w.shape) {
    case WallShape::Plane:
      unit(w.normal, "Plane.normal");
      break;
    case WallShape::Rectangle:
      w.normal = w.edge1.cross(w.edge2);
      if (!(w.normal.norm() > 0) || !w.normal.allFinite())
        throw_invalid("Rectangle.edge2", "finite and not parallel to edge1", w.edge2.transpose());
      w.normal.normalize();
      break;
    case WallShape::Cylinder:
      unit(w.axis, "Cylinder.axis");
      if (!(w.radius > 0) || !std::isfinite(w.radius))
        throw_invalid("Cylinder.radius", "positive and finite (m)", w.radius);
      if (!std::isfinite(w.length)) throw_invalid("Cylinder.length", "finite (m)", w.length);
      break;
    case WallShape::Mesh: {
      if (!w.mesh || w.mesh->triangles.empty())
        throw_invalid("Mesh.triangles", "at least one triangle", 0);
      const int nv = static_cast<int>(w.mesh->vertices.size());
      for (const Vec3& v : w.mesh->vertices)
        if (!v.allFinite()) throw_invalid("Mesh.vertices", "finite (m)", v.transpose());
      for (const auto& t : w.mesh->triangles)
        for (int k : t)
          if (k < 0 || k >= nv)
            throw_invalid("Mesh.triangles", "vertex indices in [0, " + std::to_string(nv) + ")", k);
      reach = w.mesh->radius_about(w.origin);
      break;
    }
  }
  if (w.material >= n_materials)
    throw_invalid("Wall.material", "a material known to the simulation or None (rigid)",
                  w.material);
  return w;
}

int WallSet::add(const Wall& w, Real reach) {
  walls_.push_back(w);
  wall_reach_.push_back(reach);
  primitives_.first.push_back(static_cast<Index>(primitives_.wall.size()));
  primitives_.wall.insert(primitives_.wall.end(), w.primitives(),
                          static_cast<int>(walls_.size()) - 1);
  mesh_bins_valid_.push_back(0);
  return static_cast<int>(walls_.size()) - 1;
}

void WallSet::set_motion(int index, const Vec3& velocity, const Vec3& angular_velocity,
                         const Vec3& origin) {
  if (index < 0 || index >= static_cast<int>(walls_.size()))
    throw_invalid("wall index", "in [0, " + std::to_string(walls_.size()) + ")", index);
  for (const Vec3* v : {&velocity, &angular_velocity, &origin})
    if (!v->allFinite()) throw_invalid("Wall motion", "finite", v->transpose());
  Wall& w = walls_[index];
  w.velocity = velocity;
  w.angular_velocity = angular_velocity;
  if (w.shape == WallShape::Mesh && origin != w.origin)
    wall_reach_[index] = w.mesh->radius_about(origin);
  w.origin = origin;
}

void WallSet::set_servo(int index, const Servo& servo) {
  if (index < 0 || index >= static_cast<int>(walls_.size()))
    throw_invalid("wall index", "in [0, " + std::to_string(walls_.size()) + ")", index);
  Servo s = servo;
  if (s.enabled) {
    const Real len = s.direction.norm();
    if (!(len > 0) || !std::isfinite(len))
      throw_invalid("Servo.direction", "a non-zero finite vector", s.direction.transpose());
    s.direction /= len;
    if (!(s.gain > 0) || !std::isfinite(s.gain))
      throw_invalid("Servo.gain", "positive and finite ((m/s)/N)", s.gain);
    if (!(s.max_speed > 0) || !std::isfinite(s.max_speed))
      throw_invalid("Servo.max_speed", "positive and finite (m/s)", s.max_speed);
    if (!std::isfinite(s.target_force))
      throw_invalid("Servo.target_force", "finite (N)", s.target_force);
    if (!(s.integral_gain >= 0) || !std::isfinite(s.integral_gain))
      throw_invalid("Servo.integral_gain", "non-negative and finite ((m/s)/(N s))",
                    s.integral_gain);
  }
  // A new target or gain on a wall already under PI control keeps the integrated error.
  const Servo& old = walls_[index].servo;
  s.integral = s.enabled && old.enabled && s.integral_gain > 0 ? old.integral : 0;
  walls_[index].servo = s;
  update_any_servo();
}

void WallSet::update_any_servo() {
  any_servo_ = false;
  for (const Wall& w : walls_) any_servo_ = any_servo_ || w.servo.enabled;
}

void WallSet::set_law_materials(const MaterialTable& materials) {
  for (Wall& w : walls_) w.law_material = w.material < 0 ? materials.rigid_index() : w.material;
}

void WallSet::build_mesh_bins(Real margin, Real cutoff) {
  for (std::size_t w = 0; w < walls_.size(); ++w) {
    if (walls_[w].shape != WallShape::Mesh) continue;
    if (!mesh_bins_valid_[w] || w >= wall_shift_.size() || wall_shift_[w] > 0 ||
        margin > mesh_bin_margin_)
      walls_[w].mesh->build_bins(margin, cutoff);
    mesh_bins_valid_[w] = 1;
  }
  mesh_bin_margin_ = std::max(mesh_bin_margin_, margin);
}

void WallSet::reduce_loads(const Communicator& comm) {
  if (walls_.empty()) return;
  std::vector<Real> loads(6 * walls_.size());
  for (std::size_t w = 0; w < walls_.size(); ++w)
    for (int c = 0; c < 3; ++c) {
      loads[6 * w + c] = walls_[w].force[c];
      loads[6 * w + 3 + c] = walls_[w].torque[c];
    }
  comm.sum_in_place(loads);
  for (std::size_t w = 0; w < walls_.size(); ++w)
    for (int c = 0; c < 3; ++c) {
      walls_[w].force[c] = loads[6 * w + c];
      walls_[w].torque[c] = loads[6 * w + 3 + c];
    }
}

void WallSet::save_state(LevelState& s) const {
  using state_io::put;
  s.reals["walls/shift"] = wall_shift_;
  for (std::size_t w = 0; w < walls_.size(); ++w) {
    const Wall& wall = walls_[w];
    const std::string key = "walls/" + std::to_string(w) + "/";
    const Vec3 geometry[] = {
        wall.point,          wall.normal,           wall.edge1,  wall.edge2, wall.axis,
        wall.velocity,       wall.angular_velocity, wall.origin, wall.force, wall.torque,
        wall.servo.direction};
    put(s, key + "vectors", geometry, std::size(geometry));
    s.reals[key + "servo"] = {
        wall.servo.enabled ? 1.0 : 0.0, wall.servo.target_force,  wall.servo.gain,
        wall.servo.max_speed,           wall.servo.integral_gain, wall.servo.integral};
    if (wall.mesh) put(s, key + "vertices", wall.mesh->vertices.data(), wall.mesh->vertices.size());
  }
}

void WallSet::check_state(const LevelState& s) const {
  const auto& shift = state_io::reals(s, "walls/shift");
  if (shift.size() != walls_.size()) throw std::runtime_error("checkpoint wall count differs");
  for (std::size_t k = 0; k < walls_.size(); ++k) {
    const std::string key = "walls/" + std::to_string(k) + "/";
    const auto finite = [&](const std::string& name, std::size_t size) {
      const auto& a = state_io::reals(s, key + name);
      if (a.size() != size)
        throw std::runtime_error("checkpoint array '" + key + name + "' has the wrong size");
      for (double x : a)
        if (!std::isfinite(x))
          throw std::runtime_error("checkpoint array '" + key + name +
                                   "' holds a non-finite value");
    };
    finite("vectors", 33);
    const std::size_t servo = state_io::reals(s, key + "servo").size();
    finite("servo", servo == 4 ? 4 : 6);
    if (walls_[k].mesh) finite("vertices", 3 * walls_[k].mesh->vertices.size());
  }
}

void WallSet::load_state(const LevelState& s) {
  using state_io::get;
  wall_shift_ = state_io::reals(s, "walls/shift");
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
    const auto& servo = state_io::reals(s, key + "servo");
    // 4 values: a checkpoint from before the PI servo (proportional only).
    if (servo.size() != 4 && servo.size() != 6)
      throw std::runtime_error("checkpoint servo state is corrupt");
    wall.servo.enabled = servo[0] != 0;
    wall.servo.target_force = servo[1];
    wall.servo.gain = servo[2];
    wall.servo.max_speed = servo[3];
    wall.servo.integral_gain = servo.size() == 6 ? servo[4] : 0;
    wall.servo.integral = servo.size() == 6 ? servo[5] : 0;
    if (wall.mesh) {
      // Own copy: the restarted mesh may not share vertices with the set-up's.
      wall.mesh = std::make_shared<TriangleMesh>(*wall.mesh);
      get(s, key + "vertices", wall.mesh->vertices.data(), wall.mesh->vertices.size());
      mesh_bins_valid_[k] = 0;  // rebuilt from these vertices at the next list build
    }
  }
  update_any_servo();
}

}  // namespace grainscale
