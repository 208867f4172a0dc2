#include "neighbor/neighbor_list.hpp"

namespace grainscale {

void build_pair_list(const ParticleStore& ps, const CellGrid& grid, Real skin, ContactList& list) {
  const Index n = ps.n_owned();
  const Vec3* x = ps.position.data();
  const Real* r = ps.radius.data();
  const GlobalId* id = ps.id.data();
  list.first.resize(n + 1);
  list.partner.clear();
  for (Index i = 0; i < n; ++i) {
    list.first[i] = static_cast<Index>(list.partner.size());
    const auto c = grid.coords(grid.cell_of[i]);
    const Vec3 xi = x[i];
    const Real ri = r[i];
    const GlobalId idi = id[i];
    for (int dz = -1; dz <= 1; ++dz) {
      const int cz = c[2] + dz;
      if (cz < 0 || cz >= grid.dims[2]) continue;
      for (int dy = -1; dy <= 1; ++dy) {
        const int cy = c[1] + dy;
        if (cy < 0 || cy >= grid.dims[1]) continue;
        for (int dx = -1; dx <= 1; ++dx) {
          const int cx = c[0] + dx;
          if (cx < 0 || cx >= grid.dims[0]) continue;
          const int cell = grid.cell_id(cx, cy, cz);
          for (Index k = grid.cell_start[cell]; k < grid.cell_start[cell + 1]; ++k) {
            const Index j = grid.particles[k];
            if (id[j] <= idi) continue;
            const Real cut = ri + r[j] + skin;
            if ((xi - x[j]).squaredNorm() < cut * cut) list.partner.push_back(j);
          }
        }
      }
    }
  }
  list.first[n] = static_cast<Index>(list.partner.size());
  list.history.assign(list.partner.size() * list.history_stride, 0.0);
}

void build_wall_list(const ParticleStore& ps, const std::vector<PlaneWall>& walls, Real skin,
                     ContactList& list) {
  const Index n = ps.n_owned();
  list.first.resize(n + 1);
  list.partner.clear();
  for (Index i = 0; i < n; ++i) {
    list.first[i] = static_cast<Index>(list.partner.size());
    for (std::size_t w = 0; w < walls.size(); ++w)
      if (walls[w].closest(ps.position[i]).distance < ps.radius[i] + skin)
        list.partner.push_back(static_cast<Index>(w));
  }
  list.first[n] = static_cast<Index>(list.partner.size());
  list.history.assign(list.partner.size() * list.history_stride, 0.0);
}

}  // namespace grainscale
