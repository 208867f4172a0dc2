#include "geometry/wall.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace grainscale {

Real Wall::advance(Real dt, Real reach) {
  if (servo.enabled) {
    const Real error = servo.target_force + force.dot(servo.direction);
    Real wanted = servo.gain * error;
    if (servo.integral_gain > 0) {
      const Real integral = servo.integral + error * dt;
      // Conditional integration: a saturated wall keeps its integral unless the error unwinds
      // it.
      const Real with_it = wanted + servo.integral_gain * integral;
      if (std::abs(with_it) <= servo.max_speed || error * with_it < 0) servo.integral = integral;
      wanted += servo.integral_gain * servo.integral;
    }
    const Real speed = std::clamp(wanted, -servo.max_speed, servo.max_speed);
    velocity = speed * servo.direction;
  }
  const Real w = angular_velocity.norm();
  const bool in_place = spins_in_place();
  if (w > 0 && !in_place) {
    const Eigen::AngleAxis<Real> turn(w * dt, angular_velocity / w);
    const Eigen::Matrix<Real, 3, 3> R = turn.toRotationMatrix();
    auto rotate_point = [&](Vec3& p) { p = origin + R * (p - origin); };
    rotate_point(point);
    normal = R * normal;
    edge1 = R * edge1;
    edge2 = R * edge2;
    axis = R * axis;
    if (mesh)
      for (Vec3& v : mesh->vertices) rotate_point(v);
  }
  const Vec3 shift = velocity * dt;
  if (shift.squaredNorm() > 0) {
    point += shift;
    origin += shift;
    if (mesh)
      for (Vec3& v : mesh->vertices) v += shift;
  }
  return shift.norm() + (in_place ? 0 : w * dt * reach);
}

bool Wall::spins_in_place() const {
  const Real w = angular_velocity.norm();
  if (w > 0 && shape == WallShape::Plane) return angular_velocity.cross(normal).norm() <= 1e-12 * w;
  if (w > 0 && shape == WallShape::Cylinder)
    return angular_velocity.cross(axis).norm() <= 1e-12 * w &&
           (origin - point).cross(axis).norm() <= 1e-12 * (origin - point).norm();
  return false;
}

Real Wall::step_bound(Real dt, Real reach) const {
  // A servo's current velocity: its max_speed is a cap, often far above what the gain gives,
  // and a servo wall pushes particles it touches (their own guard sees them move).
  return dt * (velocity.norm() + (spins_in_place() ? 0 : angular_velocity.norm() * reach));
}

}  // namespace grainscale
