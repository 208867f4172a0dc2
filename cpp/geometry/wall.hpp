// Walls: rigid bodies that particles touch through the same contact law as particle pairs
// (the wall is body j; it has its own material or is rigid).
//   Plane      infinite, one-sided: particles live on the side `normal` points to
//   Rectangle  point + a edge1 + b edge2, a, b in [0, 1]; two-sided, edges contacted
//   Cylinder   axis through `point` along unit `axis`, radius; particles inside or outside;
//              axial extent [0, length] from `point` (length <= 0: infinite); open ends
//   Mesh       triangles (TriangleMesh); two-sided; faces, edges and vertices contacted once
// Motion: translation `velocity` plus rotation `angular_velocity` about `origin` (rigid; the
// surface velocity at a contact is v + w x (c - origin)). A servo replaces the translation
// velocity each step by a PI law along `direction`,
//   v = clamp(gain e + integral_gain I, +-max_speed),  e = target - load,  I = sum e dt,
// where load = -force . direction is the force the particles push back with. I is integrated
// only while that does not drive a saturated speed further (conditional integration, the usual
// anti-windup), so the wall does not overshoot after a long approach at max_speed.
#pragma once

#include <memory>

#include "core/types.hpp"
#include "geometry/triangle_mesh.hpp"

namespace grainscale {

enum class WallShape { Plane, Rectangle, Cylinder, Mesh };

struct WallContact {
  Vec3 point;     // closest wall point
  Vec3 normal;    // unit, from the wall to the particle centre
  Real distance;  // centre to wall (signed for Plane: negative behind it)
};

struct Servo {
  bool enabled = false;
  Vec3 direction = Vec3::UnitZ();  // unit, into the material
  Real target_force = 0;           // N
  Real gain = 0;                   // (m/s)/N
  Real max_speed = 0;              // m/s
  Real integral_gain = 0;          // (m/s)/(N s); 0: proportional only
  Real integral = 0;               // N s, the integrated force error (state)
};

struct Wall {
  WallShape shape = WallShape::Plane;
  Vec3 point = Vec3::Zero();  // plane point / rectangle corner / point on cylinder axis
  Vec3 normal = Vec3::UnitZ();
  Vec3 edge1 = Vec3::Zero(), edge2 = Vec3::Zero();
  Vec3 axis = Vec3::UnitZ();
  Real radius = 0, length = 0;
  bool inside = true;
  std::shared_ptr<TriangleMesh> mesh;  // Mesh shape only

  Vec3 velocity = Vec3::Zero();
  Vec3 angular_velocity = Vec3::Zero();
  Vec3 origin = Vec3::Zero();  // rotation centre and torque reference; moves with the wall
  Servo servo;

  int material = -1;           // MaterialTable index, -1 for a rigid wall
  int law_material = -1;       // index the contact law uses (rigid pseudo-material for -1)
  Vec3 force = Vec3::Zero();   // exerted by particles on the wall at the last step
  Vec3 torque = Vec3::Zero();  // about origin

  int primitives() const {
    return shape == WallShape::Mesh ? static_cast<int>(mesh->triangles.size()) : 1;
  }
  // Closest-point geometry of a non-mesh wall for sphere centre x; false if there is none
  // (beyond the axial extent of a finite cylinder).
  // Forced inline: the wall loop calls it for every wall entry every step.
  [[gnu::always_inline]] inline bool closest(const Vec3& x, WallContact& out) const;
  Vec3 surface_velocity(const Vec3& at) const {
    return velocity + angular_velocity.cross(at - origin);
  }
  // Moves the wall rigidly over dt (servo velocity first); returns an upper bound of how far
  // any point of it within `reach` of the origin moved.
  Real advance(Real dt, Real reach);
  // How far advance() moves a point within `reach` in one step at the current velocity: the
  // guards compare it with the particles' radii.
  Real step_bound(Real dt, Real reach) const;
  // A plane spinning about its normal or a cylinder about its axis keeps its shape in place:
  // only its surface velocity changes.
  bool spins_in_place() const;
};

inline bool Wall::closest(const Vec3& x, WallContact& out) const {
  const Vec3 q = x - point;
  switch (shape) {
    case WallShape::Plane: {
      const Real s = q.dot(normal);
      out = {x - s * normal, normal, s};
      return true;
    }
    case WallShape::Rectangle: {
      const Real a = std::clamp(q.dot(edge1) / edge1.squaredNorm(), Real(0), Real(1));
      const Real b = std::clamp(q.dot(edge2) / edge2.squaredNorm(), Real(0), Real(1));
      const Vec3 p = point + a * edge1 + b * edge2;
      const Vec3 d = x - p;
      const Real dist = d.norm();
      out = {p, dist > 0 ? Vec3(d / dist) : normal, dist};
      return true;
    }
    case WallShape::Cylinder: {
      const Real h = q.dot(axis);
      if (length > 0 && (h < 0 || h > length)) return false;
      const Vec3 rho = q - h * axis;
      const Real r = rho.norm();
      if (r == 0) return false;  // on the axis: no defined normal (far from the wall anyway)
      const Vec3 radial = rho / r;
      const Vec3 p = point + h * axis + radius * radial;
      out = inside ? WallContact{p, -radial, radius - r} : WallContact{p, radial, r - radius};
      return true;
    }
    case WallShape::Mesh:
      return false;
  }
  return false;
}

}  // namespace grainscale
