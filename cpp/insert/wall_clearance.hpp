// WallClearance: whether a sphere that insertion is about to place would touch a wall of the
// level, by the contact code's own test (geometry/wall_distance.hpp), against the walls' current
// positions. Built once per placement pass (a packing, a stream batch) for the box the centres
// can take: each mesh wall contributes only its triangles that come within the largest radius of
// that box, binned with that radius as margin, so one cell lookup yields every triangle a sphere
// may touch, however many triangles the mesh has.
#pragma once

#include <vector>

#include "core/types.hpp"
#include "geometry/triangle_bins.hpp"
#include "geometry/wall.hpp"

namespace grainscale {

class WallClearance {
 public:
  WallClearance() = default;  // no walls
  // Centres will lie in [lo, hi] with radii up to max_radius. The walls must outlive this.
  WallClearance(const std::vector<Wall>& walls, const Vec3& lo, const Vec3& hi, Real max_radius);

  bool empty() const { return simple_.empty() && meshes_.empty(); }
  // Whether the sphere (x, r), r <= max_radius, touches no wall.
  bool clear(const Vec3& x, Real r) const;
  // Whether every sphere of radius r (<= max_radius) centred within `reach` of x touches one
  // single wall: no free centre can lie in that ball (lets a voxel sampler drop it).
  bool blocks(const Vec3& x, Real reach, Real r) const;
  // Whether a wall lies across the segment [a, b] (geometry/segment_crossing.hpp); complete for
  // segments inside [lo, hi] grown by max_radius.
  bool separates(const Vec3& a, const Vec3& b) const;

 private:
  struct MeshPart {
    const TriangleMesh* mesh;
    TriangleBins bins;
  };
  std::vector<const Wall*> simple_;
  std::vector<MeshPart> meshes_;
  mutable std::vector<int> scratch_;  // query buffer: one thread per WallClearance
};

}  // namespace grainscale
