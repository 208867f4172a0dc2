// Plane walls: an infinite one-sided plane or a bounded, two-sided rectangle.
// A wall is body j of the contact law: rigid (material = rigid pseudo-material) or with its own
// material. It may translate at a prescribed velocity.
#pragma once

#include <algorithm>
#include <cmath>

#include "core/types.hpp"

namespace grainscale {

struct WallContactGeometry {
  Vec3 normal;    // unit, from the wall to the particle centre
  Real distance;  // from the particle centre to the closest wall point
};

struct PlaneWall {
  enum class Shape { Infinite, Rectangle };
  Shape shape = Shape::Infinite;
  Vec3 point = Vec3::Zero();    // a point of the plane / the rectangle's corner; torque reference
  Vec3 normal = Vec3::UnitZ();  // unit; for Infinite the side particles live on
  Vec3 edge1 = Vec3::Zero(), edge2 = Vec3::Zero();  // Rectangle spans point + a edge1 + b edge2
  Vec3 velocity = Vec3::Zero();
  int material = -1;      // index into MaterialTable, -1 for a rigid wall
  int law_material = -1;  // index used by the contact law (rigid pseudo-material for -1)
  // Results of the last force evaluation: force and torque exerted by particles on the wall.
  Vec3 force = Vec3::Zero();
  Vec3 torque = Vec3::Zero();

  // Closest-point geometry for a sphere centre x. For an infinite plane the distance is signed
  // (negative behind the plane, which still pushes the particle back out).
  inline WallContactGeometry closest(const Vec3& x) const;
  // Translates the wall by its velocity over dt.
  void advance(Real dt) { point += velocity * dt; }
};

inline WallContactGeometry PlaneWall::closest(const Vec3& x) const {
  const Vec3 q = x - point;
  if (shape == Shape::Infinite) return {normal, q.dot(normal)};
  const Real a = std::clamp(q.dot(edge1) / edge1.squaredNorm(), Real(0), Real(1));
  const Real b = std::clamp(q.dot(edge2) / edge2.squaredNorm(), Real(0), Real(1));
  const Vec3 d = q - a * edge1 - b * edge2;
  const Real dist = d.norm();
  if (dist == 0) return {normal, 0};
  return {d / dist, dist};
}

}  // namespace grainscale
