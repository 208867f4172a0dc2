#include "neighbor/neighbor_list.hpp"

#include <algorithm>

namespace grainscale {

void build_pair_list(const ParticleStore& ps, const CellGrid& grid, Real skin, ContactList& list) {
  const Index n = ps.n_owned();
  const Vec3* x = ps.position.data();
  const Real* r = ps.radius.data();
  const GlobalId* id = ps.id.data();
  Real r_max = 0;
  for (Index i = 0; i < ps.n_local(); ++i) r_max = std::max(r_max, r[i]);
  const auto R = grid.reach(2 * r_max + skin);
  list.first.resize(n + 1);
  list.partner.clear();
  for (Index i = 0; i < n; ++i) {
    list.first[i] = static_cast<Index>(list.partner.size());
    const auto c = grid.coords(grid.cell_of[i]);
    const Vec3 xi = x[i];
    const Real ri = r[i];
    const GlobalId idi = id[i];
    // Cells adjacent along x are adjacent in `grid.particles`, so each (dy, dz) row of the
    // stencil is one contiguous range of candidates.
    const int x0 = std::max(c[0] - R[0], 0), x1 = std::min(c[0] + R[0], grid.dims[0] - 1);
    for (int cz = std::max(c[2] - R[2], 0); cz <= std::min(c[2] + R[2], grid.dims[2] - 1); ++cz) {
      for (int cy = std::max(c[1] - R[1], 0); cy <= std::min(c[1] + R[1], grid.dims[1] - 1); ++cy) {
        const Index begin = grid.cell_start[grid.cell_id(x0, cy, cz)];
        const Index end = grid.cell_start[grid.cell_id(x1, cy, cz) + 1];
        for (Index k = begin; k < end; ++k) {
          const Index j = grid.particles[k];
          if (id[j] <= idi) continue;
          const Real cut = ri + r[j] + skin;
          if ((xi - x[j]).squaredNorm() < cut * cut) list.partner.push_back(j);
        }
      }
    }
  }
  list.first[n] = static_cast<Index>(list.partner.size());
  list.history.assign(list.partner.size() * list.history_stride, 0.0);
  list.touching.assign(list.partner.size(), 0);
}

void build_wall_list(const ParticleStore& ps, const std::vector<Wall>& walls,
                     const std::vector<Index>& primitive_first, Real skin, ContactList& list) {
  const Index n = ps.n_owned();
  list.first.resize(n + 1);
  list.partner.clear();
  std::vector<int> candidates;
  for (Index i = 0; i < n; ++i) {
    list.first[i] = static_cast<Index>(list.partner.size());
    const Vec3& x = ps.position[i];
    const Real reach = ps.radius[i] + skin;
    for (std::size_t w = 0; w < walls.size(); ++w) {
      const Wall& wall = walls[w];
      if (wall.shape == WallShape::Mesh) {
        wall.mesh->candidates(x, candidates);
        std::sort(candidates.begin(), candidates.end());
        for (int t : candidates)
          if ((wall.mesh->closest(t, x).point - x).squaredNorm() < reach * reach)
            list.partner.push_back(primitive_first[w] + t);
      } else {
        WallContact c;
        if (wall.closest(x, c) && c.distance < reach) list.partner.push_back(primitive_first[w]);
      }
    }
  }
  list.first[n] = static_cast<Index>(list.partner.size());
  list.history.assign(list.partner.size() * list.history_stride, 0.0);
  list.touching.assign(list.partner.size(), 0);
}

}  // namespace grainscale
