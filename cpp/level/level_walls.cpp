// Level: its wall set (adding a wall with its checks, prescribed motion, servo control).
#include <cmath>
#include <string>

#include "core/errors.hpp"
#include "level/level.hpp"

namespace grainscale {

int Level::add_wall(const Wall& wall) {
  Wall w = wall;
  for (const Vec3* v : {&w.point, &w.velocity, &w.angular_velocity, &w.origin})
    if (!v->allFinite()) throw_invalid("Wall motion and position", "finite", v->transpose());
  auto unit = [](Vec3& v, const char* name) {
    const Real len = v.norm();
    if (!(len > 0) || !std::isfinite(len))
      throw_invalid(name, "a non-zero finite vector", v.transpose());
    v /= len;
  };
  Real reach =
      (domain_.hi - domain_.lo).norm() + (w.origin - 0.5 * (domain_.lo + domain_.hi)).norm();
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
  if (w.material >= materials_.n_materials())
    throw_invalid("Wall.material", "a material known to the simulation or None (rigid)",
                  w.material);
  if (lists_valid_) save_histories();
  walls_.push_back(w);
  wall_reach_.push_back(reach);
  primitives_.first.push_back(static_cast<Index>(primitives_.wall.size()));
  primitives_.wall.insert(primitives_.wall.end(), w.primitives(),
                          static_cast<int>(walls_.size()) - 1);
  mesh_bins_valid_.push_back(0);
  lists_valid_ = false;
  forces_valid_ = false;
  return static_cast<int>(walls_.size()) - 1;
}

void Level::set_wall_motion(int index, const Vec3& velocity, const Vec3& angular_velocity,
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
  forces_valid_ = false;
}

void Level::set_wall_servo(int index, const Servo& servo) {
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
  any_servo_ = false;
  for (const Wall& w : walls_) any_servo_ = any_servo_ || w.servo.enabled;
}

}  // namespace grainscale
