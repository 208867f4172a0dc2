// Distance from a sphere centre to a wall, measured as the contact loop measures it
// (contact/wall_loop.hpp, through Wall::closest and TriangleMesh::closest): a sphere (x, r)
// touches the wall exactly when this distance is below r.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "geometry/wall.hpp"

namespace grainscale {

// Non-mesh walls: signed for a plane (negative behind it); +inf where a finite cylinder has no
// closest point (beyond its open ends).
inline Real wall_distance(const Wall& wall, const Vec3& x) {
  WallContact g;
  return wall.closest(x, g) ? g.distance : std::numeric_limits<Real>::infinity();
}

// An upper bound of wall_distance over the ball (x, reach): the distance is 1-Lipschitz where it
// is finite, and a finite cylinder's distance jumps to +inf past an open end.
inline Real wall_distance_bound(const Wall& wall, const Vec3& x, Real reach) {
  if (wall.shape == WallShape::Cylinder && wall.length > 0) {
    const Real h = (x - wall.point).dot(wall.axis);
    if (h < reach || h > wall.length - reach) return std::numeric_limits<Real>::infinity();
  }
  return wall_distance(wall, x) + reach;
}

// Distance from x to the nearest of the given triangles (+inf for none); the search stops as soon
// as one is nearer than `stop_below`.
inline Real mesh_distance(const TriangleMesh& mesh, const std::vector<int>& triangles,
                          const Vec3& x, Real stop_below = 0) {
  Real d2 = std::numeric_limits<Real>::infinity();
  const Real stop2 = stop_below * stop_below;
  for (int t : triangles) {
    d2 = std::min(d2, (x - mesh.closest(t, x).point).squaredNorm());
    if (d2 < stop2) break;
  }
  return std::sqrt(d2);
}

}  // namespace grainscale
