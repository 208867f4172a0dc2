// Whether a straight segment [a, b] passes through a wall's surface: the line-of-sight test of
// the flux insertion (a child grain goes only where the parent's material can reach, no wall
// between it and the nearest parent grain; coupling/flux_inserter.hpp). A segment that ends on
// the surface crosses it; one lying in the surface's plane (grazing) does not.
#pragma once

#include <cmath>

#include "geometry/wall.hpp"

namespace grainscale {

// Segment against triangle (v0, v1, v2), after Moller & Trumbore (1997), "Fast, minimum storage
// ray-triangle intersection", Journal of Graphics Tools 2(1), 21-28, with the ray parameter
// limited to the segment.
inline bool segment_crosses_triangle(const Vec3& a, const Vec3& b, const Vec3& v0, const Vec3& v1,
                                     const Vec3& v2) {
  const Vec3 d = b - a, e1 = v1 - v0, e2 = v2 - v0;
  const Vec3 p = d.cross(e2);
  const Real det = e1.dot(p);
  if (det == 0) return false;  // parallel to the triangle's plane
  const Real inv = 1 / det;
  const Vec3 s = a - v0;
  const Real u = s.dot(p) * inv;
  if (u < 0 || u > 1) return false;
  const Vec3 q = s.cross(e1);
  const Real v = d.dot(q) * inv;
  if (v < 0 || u + v > 1) return false;
  const Real t = e2.dot(q) * inv;
  return t >= 0 && t <= 1;
}

// Non-mesh walls (wall.hpp): a plane's whole surface, a rectangle (two triangles), a cylinder's
// mantle within its axial extent (the roots of |radial part of a + t (b - a)|^2 = R^2 in [0, 1]).
inline bool segment_crosses(const Wall& w, const Vec3& a, const Vec3& b) {
  switch (w.shape) {
    case WallShape::Plane:
      return ((a - w.point).dot(w.normal) < 0) != ((b - w.point).dot(w.normal) < 0);
    case WallShape::Rectangle: {
      const Vec3 c = w.point + w.edge1 + w.edge2;
      return segment_crosses_triangle(a, b, w.point, w.point + w.edge1, c) ||
             segment_crosses_triangle(a, b, w.point, c, w.point + w.edge2);
    }
    case WallShape::Cylinder: {
      const Vec3 s = a - w.point, d = b - a;
      const Vec3 u = s - s.dot(w.axis) * w.axis, du = d - d.dot(w.axis) * w.axis;
      const Real A = du.squaredNorm(), B = 2 * u.dot(du), C = u.squaredNorm() - w.radius * w.radius;
      if (A == 0) return false;  // along the axis: the radial distance does not change
      const Real disc = B * B - 4 * A * C;
      if (disc < 0) return false;
      const Real root = std::sqrt(disc);
      for (const Real t : {(-B - root) / (2 * A), (-B + root) / (2 * A)}) {
        if (t < 0 || t > 1) continue;
        const Real h = (s + t * d).dot(w.axis);
        if (w.length <= 0 || (h >= 0 && h <= w.length)) return true;
      }
      return false;
    }
    case WallShape::Mesh:
      break;  // by triangle (WallClearance::separates)
  }
  return false;
}

}  // namespace grainscale
