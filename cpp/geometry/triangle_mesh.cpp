#include "geometry/triangle_mesh.hpp"

#include <algorithm>
#include <cmath>

namespace grainscale {

TriangleHit TriangleMesh::closest(int t, const Vec3& p) const {
  const auto& tri = triangles[t];
  const Vec3& a = vertices[tri[0]];
  const Vec3& b = vertices[tri[1]];
  const Vec3& c = vertices[tri[2]];
  auto edge = [&](int i, int j, const Vec3& q) {
    return TriangleHit{q, 1, std::min(tri[i], tri[j]), std::max(tri[i], tri[j])};
  };
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const Real d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {a, 2, tri[0], -1};
  const Vec3 bp = p - b;
  const Real d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {b, 2, tri[1], -1};
  const Real vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return edge(0, 1, a + (d1 / (d1 - d3)) * ab);
  const Vec3 cp = p - c;
  const Real d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {c, 2, tri[2], -1};
  const Real vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return edge(0, 2, a + (d2 / (d2 - d6)) * ac);
  const Real va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return edge(1, 2, b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b));
  const Real denom = 1 / (va + vb + vc);
  return {a + ab * (vb * denom) + ac * (vc * denom), 0, -1, -1};
}

Real TriangleMesh::radius_about(const Vec3& origin) const {
  Real r2 = 0;
  for (const Vec3& v : vertices) r2 = std::max(r2, (v - origin).squaredNorm());
  return std::sqrt(r2);
}

}  // namespace grainscale
