// Regions for insertion and outlets: a parallelepiped (corner + a e1 + b e2 + c e3, a, b, c in
// [0, 1]; an axis-aligned box is the special case), a finite cylinder (centre at mid-height,
// unit axis, radius, height) or, for packing only, the interior of a closed triangle mesh
// (geometry/closed_mesh.hpp: a sphere is inside when its centre is and the surface is at least r
// away). Faces for streams: a parallelogram (corner, edge1, edge2) or a disc
// (centre, normal, radius); a face extruded along its normal is a region (the insertion slab).
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "geometry/closed_mesh.hpp"
#include "insert/random.hpp"

namespace grainscale {

class Region {
 public:
  enum class Kind { Parallelepiped, Cylinder, Mesh };

  static Region box(const Vec3& lo, const Vec3& hi);
  static Region parallelepiped(const Vec3& corner, const Vec3& e1, const Vec3& e2, const Vec3& e3);
  // centre: the middle of the axis segment; axis need not be normalised.
  static Region cylinder(const Vec3& centre, const Vec3& axis, Real radius, Real height);
  // Interior of a closed, consistently oriented triangle surface; throws InvalidArgument naming
  // `what` otherwise.
  static Region mesh(const std::vector<Vec3>& vertices,
                     const std::vector<std::array<int, 3>>& triangles, const std::string& what);

  Kind kind() const { return kind_; }
  Real volume() const;
  // Axis-aligned bounding box.
  void bounds(Vec3& lo, Vec3& hi) const;
  // Whether the sphere (x, r) lies entirely inside (r = 0: the point x).
  bool contains(const Vec3& x, Real r = 0) const;
  // Whether a sphere of radius r fits inside at all (Mesh: fits inside the bounding box, a
  // necessary condition only).
  bool fits(Real r) const;
  // A centre drawn uniformly from the positions where a sphere of radius r lies inside
  // (requires fits(r)); consumes exactly three uniform numbers. Mesh: uniform in the bounding box
  // shrunk by r, which holds every such position; the caller rejects with contains().
  Vec3 sample(Rng& rng, Real r) const;
  // Whether sample() always returns a centre that contains() accepts.
  bool samples_inside() const { return kind_ != Kind::Mesh; }

 private:
  Kind kind_ = Kind::Parallelepiped;
  Vec3 origin_ = Vec3::Zero();  // corner / centre
  Vec3 e_[3];                   // edges / (radial u, radial v, unit axis)
  Vec3 dual_[3];                // parallelepiped: x - origin = sum_k (dual_k . (x - origin)) e_k
  Real radius_ = 0, height_ = 0;
  std::shared_ptr<const ClosedMesh> mesh_;  // Mesh kind; shared by copies (immutable)
};

class Face {
 public:
  enum class Kind { Parallelogram, Disc };

  static Face rectangle(const Vec3& corner, const Vec3& edge1, const Vec3& edge2);
  static Face disc(const Vec3& centre, const Vec3& normal, Real radius);

  Kind kind() const { return kind_; }
  // Unit normal: edge1 x edge2 for a rectangle, the given normal for a disc.
  const Vec3& normal() const { return normal_; }
  Real area() const;
  // The face swept a distance `thickness` along `direction` (+normal or -normal).
  Region slab(const Vec3& direction, Real thickness) const;
  // Whether a sphere of radius r fits inside the face outline.
  bool fits(Real r) const;

 private:
  Kind kind_ = Kind::Parallelogram;
  Vec3 origin_ = Vec3::Zero(), e1_ = Vec3::Zero(), e2_ = Vec3::Zero(), normal_ = Vec3::UnitZ();
  Real radius_ = 0;
};

}  // namespace grainscale
