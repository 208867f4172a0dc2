// FieldGrid: a regular grid of hexahedral cells (origin, edge lengths per axis, cell counts) on
// which Eulerian fields are averaged (DESIGN.md 2.7) and levels of a hierarchy exchange data
// (DESIGN.md 4). Cell c = ix + nx (iy + ny iz).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include "core/types.hpp"

namespace grainscale {

struct FieldGrid {
  Vec3 origin = Vec3::Zero();
  Vec3 edge = Vec3::Ones();
  std::array<int, 3> dims{1, 1, 1};

  int n_cells() const { return dims[0] * dims[1] * dims[2]; }
  Real cell_volume() const { return edge.prod(); }
  Vec3 upper() const {
    return origin + Vec3(edge[0] * dims[0], edge[1] * dims[1], edge[2] * dims[2]);
  }
  int index(int ix, int iy, int iz) const { return ix + dims[0] * (iy + dims[1] * iz); }
  std::array<int, 3> coords(int c) const {
    return {c % dims[0], (c / dims[0]) % dims[1], c / (dims[0] * dims[1])};
  }
  Vec3 centre(int c) const {
    const auto k = coords(c);
    return origin + Vec3((k[0] + 0.5) * edge[0], (k[1] + 0.5) * edge[1], (k[2] + 0.5) * edge[2]);
  }
  // Cell holding x, or -1 outside the grid (the upper faces belong to the last cells).
  int cell_of(const Vec3& x) const {
    int k[3];
    for (int a = 0; a < 3; ++a) {
      const Real f = (x[a] - origin[a]) / edge[a];
      if (!(f >= 0) || f > dims[a]) return -1;
      k[a] = std::min(static_cast<int>(f), dims[a] - 1);
    }
    return index(k[0], k[1], k[2]);
  }
};

}  // namespace grainscale
