#include "insert/region.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"

namespace grainscale {

Region Region::box(const Vec3& lo, const Vec3& hi) {
  for (int a = 0; a < 3; ++a)
    if (!(hi[a] > lo[a]) || !std::isfinite(hi[a] - lo[a]))
      throw_invalid("Box.hi", "greater than Box.lo on every axis (m)", hi.transpose());
  const Vec3 d = hi - lo;
  return parallelepiped(lo, Vec3(d[0], 0, 0), Vec3(0, d[1], 0), Vec3(0, 0, d[2]));
}

Region Region::parallelepiped(const Vec3& corner, const Vec3& e1, const Vec3& e2, const Vec3& e3) {
  Region r;
  r.kind_ = Kind::Parallelepiped;
  r.origin_ = corner;
  r.e_[0] = e1;
  r.e_[1] = e2;
  r.e_[2] = e3;
  const Real v = e1.dot(e2.cross(e3));
  if (!(std::abs(v) > 0) || !std::isfinite(v) || !corner.allFinite())
    throw_invalid("Region edges", "finite and spanning a volume", v);
  r.dual_[0] = e2.cross(e3) / v;
  r.dual_[1] = e3.cross(e1) / v;
  r.dual_[2] = e1.cross(e2) / v;
  return r;
}

Region Region::cylinder(const Vec3& centre, const Vec3& axis, Real radius, Real height) {
  if (!centre.allFinite()) throw_invalid("Cylinder.centre", "finite (m)", centre.transpose());
  const Real len = axis.norm();
  if (!(len > 0) || !std::isfinite(len))
    throw_invalid("Cylinder.axis", "a non-zero finite vector", axis.transpose());
  if (!(radius > 0) || !std::isfinite(radius))
    throw_invalid("Cylinder.radius", "positive and finite (m)", radius);
  if (!(height > 0) || !std::isfinite(height))
    throw_invalid("Cylinder.height", "positive and finite (m)", height);
  Region r;
  r.kind_ = Kind::Cylinder;
  r.origin_ = centre;
  const Vec3 w = axis / len;
  // Any unit vector perpendicular to the axis, then the third by a cross product.
  const Vec3 helper = std::abs(w[0]) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  r.e_[0] = w.cross(helper).normalized();
  r.e_[1] = w.cross(r.e_[0]);
  r.e_[2] = w;
  r.radius_ = radius;
  r.height_ = height;
  return r;
}

Region Region::mesh(const std::vector<Vec3>& vertices,
                    const std::vector<std::array<int, 3>>& triangles, const std::string& what) {
  Region r;
  r.kind_ = Kind::Mesh;
  r.mesh_ = std::make_shared<const ClosedMesh>(vertices, triangles, what);
  return r;
}

Real Region::volume() const {
  if (kind_ == Kind::Mesh) return mesh_->volume();
  if (kind_ == Kind::Cylinder) return M_PI * radius_ * radius_ * height_;
  return std::abs(e_[0].dot(e_[1].cross(e_[2])));
}

void Region::bounds(Vec3& lo, Vec3& hi) const {
  if (kind_ == Kind::Mesh) return mesh_->bounds(lo, hi);
  if (kind_ == Kind::Cylinder) {
    const Vec3& w = e_[2];
    for (int a = 0; a < 3; ++a) {
      const Real ext =
          0.5 * height_ * std::abs(w[a]) + radius_ * std::sqrt(std::max(Real(0), 1 - w[a] * w[a]));
      lo[a] = origin_[a] - ext;
      hi[a] = origin_[a] + ext;
    }
    return;
  }
  lo = hi = origin_;
  for (int k = 0; k < 8; ++k) {
    Vec3 p = origin_;
    for (int e = 0; e < 3; ++e)
      if (k & (1 << e)) p += e_[e];
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
}

bool Region::contains(const Vec3& x, Real r) const {
  if (kind_ == Kind::Mesh) return mesh_->inside(x) && !mesh_->near_surface(x, r);
  const Vec3 q = x - origin_;
  if (kind_ == Kind::Cylinder) {
    const Real z = q.dot(e_[2]);
    if (std::abs(z) > 0.5 * height_ - r) return false;
    const Real rho2 = (q - z * e_[2]).squaredNorm();
    const Real room = radius_ - r;
    return room >= 0 && rho2 <= room * room;
  }
  for (int k = 0; k < 3; ++k) {
    // dual_k . q is the coordinate along e_k; 1/|dual_k| is the width across that pair of faces.
    const Real c = dual_[k].dot(q);
    const Real margin = r * dual_[k].norm();
    if (c < margin || c > 1 - margin) return false;
  }
  return true;
}

bool Region::fits(Real r) const {
  if (kind_ == Kind::Mesh) {
    Vec3 lo, hi;
    mesh_->bounds(lo, hi);
    return 2 * r <= (hi - lo).minCoeff();
  }
  if (kind_ == Kind::Cylinder) return r <= radius_ && 2 * r <= height_;
  for (int k = 0; k < 3; ++k)
    if (2 * r * dual_[k].norm() > 1) return false;
  return true;
}

Vec3 Region::sample(Rng& rng, Real r) const {
  const Real u0 = uniform01(rng), u1 = uniform01(rng), u2 = uniform01(rng);
  if (kind_ == Kind::Cylinder) {
    const Real rho = (radius_ - r) * std::sqrt(u0);
    const Real phi = 2 * M_PI * u1;
    const Real z = (u2 - 0.5) * (height_ - 2 * r);
    return origin_ + rho * std::cos(phi) * e_[0] + rho * std::sin(phi) * e_[1] + z * e_[2];
  }
  const Real u[3] = {u0, u1, u2};
  if (kind_ == Kind::Mesh) {
    Vec3 lo, hi;
    mesh_->bounds(lo, hi);
    Vec3 x;
    for (int a = 0; a < 3; ++a) x[a] = lo[a] + r + u[a] * (hi[a] - lo[a] - 2 * r);
    return x;
  }
  Vec3 x = origin_;
  for (int k = 0; k < 3; ++k) {
    const Real margin = r * dual_[k].norm();
    x += (margin + u[k] * (1 - 2 * margin)) * e_[k];
  }
  return x;
}

Face Face::rectangle(const Vec3& corner, const Vec3& edge1, const Vec3& edge2) {
  if (!corner.allFinite()) throw_invalid("RectangleFace.corner", "finite (m)", corner.transpose());
  const Vec3 n = edge1.cross(edge2);
  if (!(n.norm() > 0) || !n.allFinite())
    throw_invalid("RectangleFace.edge2", "finite and not parallel to edge1", edge2.transpose());
  Face f;
  f.kind_ = Kind::Parallelogram;
  f.origin_ = corner;
  f.e1_ = edge1;
  f.e2_ = edge2;
  f.normal_ = n.normalized();
  return f;
}

Face Face::disc(const Vec3& centre, const Vec3& normal, Real radius) {
  if (!centre.allFinite()) throw_invalid("DiscFace.centre", "finite (m)", centre.transpose());
  const Real len = normal.norm();
  if (!(len > 0) || !std::isfinite(len))
    throw_invalid("DiscFace.normal", "a non-zero finite vector", normal.transpose());
  if (!(radius > 0) || !std::isfinite(radius))
    throw_invalid("DiscFace.radius", "positive and finite (m)", radius);
  Face f;
  f.kind_ = Kind::Disc;
  f.origin_ = centre;
  f.normal_ = normal / len;
  f.radius_ = radius;
  return f;
}

Real Face::area() const {
  if (kind_ == Kind::Disc) return M_PI * radius_ * radius_;
  return e1_.cross(e2_).norm();
}

Region Face::slab(const Vec3& direction, Real thickness) const {
  if (kind_ == Kind::Disc)
    return Region::cylinder(origin_ + 0.5 * thickness * direction, direction, radius_, thickness);
  return Region::parallelepiped(origin_, e1_, e2_, thickness * direction);
}

bool Face::fits(Real r) const {
  if (kind_ == Kind::Disc) return r <= radius_;
  // Widths of the parallelogram across its two pairs of sides.
  const Real area2 = e1_.cross(e2_).norm();
  return 2 * r <= area2 / e1_.norm() && 2 * r <= area2 / e2_.norm();
}

}  // namespace grainscale
