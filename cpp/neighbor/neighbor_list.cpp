#include "neighbor/neighbor_list.hpp"

#include <algorithm>
#include <cstdint>
#include <utility>

#include "neighbor/pair_scan_lanes.hpp"

namespace grainscale {

void build_pair_list(const ParticleStore& ps, const CellGrid& grid, Real cutoff, Real skin,
                     ContactList& list) {
  const Index n = ps.n_owned();
  const Vec3* x = ps.position.data();
  const Real* r = ps.radius.data();
  const GlobalId* id = ps.id.data();
  const auto R = grid.reach(cutoff);

  // Every unordered pair of cells is visited once: for the particle in grid slot p, the later
  // slots of its own cell and the cells "after" it (higher z, or same z and higher y, or same z
  // and y and higher x) within the reach. Cells adjacent along x are adjacent in
  // `grid.particles`, so each (dy, dz) row of the stencil is one contiguous range of slots.
  // A pair found is stored at the particle with the smaller global id when that one is owned;
  // when it is a ghost the same pair is found again between its owner and an image of the
  // other particle (which is then stored), so it is skipped here.
  PageVector<std::pair<Index, Index>>& found = list.scratch_pairs;
  found.clear();
  PageVector<Index>& count = list.scratch_count;
  count.assign(n + 1, 0);
#if defined(GRAINSCALE_PAIR_SCAN_LANES)
  // The columns take the old history's memory, whose values are dead here (saved by the
  // HistoryCarry before the build, overwritten below): 5 doubles per point, fewer than the
  // history of a bed's 3-4 entries per particle. With a buffer of their own the dense 50k
  // bed's peak memory rose 2.3 MiB, above LIGGGHTS'.
  detail::GridColumns columns;
  columns.fill(grid, x, r, id, list.history);
  std::size_t used = 0;  // found[0, used) are the pairs; found's size is room
#endif
  const int nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
  for (int cz = 0; cz < nz; ++cz)
    for (int cy = 0; cy < ny; ++cy)
      for (int cx = 0; cx < nx; ++cx) {
        const int cell = grid.cell_id(cx, cy, cz);
        const int x0 = std::max(cx - R[0], 0), x1 = std::min(cx + R[0], nx - 1);
        for (Index p = grid.cell_start[cell]; p < grid.cell_start[cell + 1]; ++p) {
          const Index a = grid.particles[p];
          const Vec3 xa = x[a];
          const Real ra = r[a] + skin;
          const GlobalId ida = id[a];
          auto scan = [&](Index begin, Index end) {
#if defined(GRAINSCALE_PAIR_SCAN_LANES)
            if (end <= begin) return;
            const std::size_t room = used + static_cast<std::size_t>(end - begin) + 8;
            if (room > found.size()) found.resize(std::max(room, 2 * found.size()));
            used = detail::scan_lanes(columns, begin, end, a, xa, ra, ida, n, found.data(), used);
#else
            for (Index q = begin; q < end; ++q) {
              const Index b = grid.particles[q];
              const Real cut = ra + r[b];
              if ((xa - x[b]).squaredNorm() >= cut * cut) continue;
              const bool a_first = ida < id[b];
              const Index owner = a_first ? a : b, partner = a_first ? b : a;
              if (owner >= n) continue;  // a ghost: stored through its owner
              found.emplace_back(owner, partner);
            }
#endif
          };
          // Own row: later slots of this cell and the cells after it along x.
          scan(p + 1, grid.cell_start[grid.cell_id(x1, cy, cz) + 1]);
          for (int dz = 0; dz <= R[2]; ++dz) {
            const int z = cz + dz;
            if (z >= nz) break;
            for (int dy = dz == 0 ? 1 : -R[1]; dy <= R[1]; ++dy) {
              const int y = cy + dy;
              if (y < 0) continue;
              if (y >= ny) break;
              scan(grid.cell_start[grid.cell_id(x0, y, z)],
                   grid.cell_start[grid.cell_id(x1, y, z) + 1]);
            }
          }
        }
      }

#if defined(GRAINSCALE_PAIR_SCAN_LANES)
  found.resize(used);
#endif
  for (const auto& pair : found) ++count[pair.first];
  // Compressed rows by owner, entries in the order found.
  list.first.resize(n + 1);
  Index offset = 0;
  for (Index i = 0; i < n; ++i) {
    list.first[i] = offset;
    offset += count[i];
    count[i] = list.first[i];  // becomes the fill position
  }
  list.first[n] = offset;
  // Every slot is written below: the old contents need neither keeping nor clearing.
  reserve_growing(list.partner, static_cast<std::size_t>(offset));
  list.partner.resize(offset);
  for (const auto& [owner, partner] : found) list.partner[count[owner]++] = partner;
  assign_growing(list.history, list.partner.size() * list.history_stride, 0.0);
  assign_growing<std::uint8_t>(list.touching, list.partner.size(), 0);
  index_rows(list);
}

void index_rows(ContactList& list) {
  // Branch-free: a branch per particle would mostly mispredict.
  const Index n = list.first.empty() ? 0 : static_cast<Index>(list.first.size()) - 1;
  list.rows.resize(n);
  Index n_rows = 0;
  for (Index i = 0; i < n; ++i) {
    list.rows[n_rows] = i;
    n_rows += list.first[i + 1] != list.first[i];
  }
  list.rows.resize(n_rows);
  // Each row's number at its first entry (a row without entries starts where the next one
  // does and is overwritten by it), then a running maximum. Offsets are clamped: a list read
  // from a file is checked elsewhere, and this must not write outside it either way.
  const Index size = static_cast<Index>(list.partner.size());
  assign_growing<Index>(list.owner, list.partner.size(), 0);
  Index* owner = list.owner.data();
  for (Index i = 0; i < n; ++i) {
    const Index k = std::clamp<Index>(list.first[i], 0, size);
    if (k < size) owner[k] = i;
  }
  for (Index k = 1; k < size; ++k) owner[k] = std::max(owner[k], owner[k - 1]);
}

void build_wall_list(const ParticleStore& ps, const std::vector<Wall>& walls,
                     const std::vector<Index>& primitive_first, Real skin, ContactList& list) {
  const Index n = ps.n_owned();
  const Vec3* x = ps.position.data();
  const Real* r = ps.radius.data();
  // The analytic walls' tests, wall by wall over blocks of particles (whose positions stay in
  // L1 for all walls): bit w of near[i] is set when particle i is within reach of wall w (the
  // first kMaskWalls walls). A plane's loop has no branch and is vectorized. One loop over the
  // particles with a switch per wall took about 10 ns per particle for six planes (the 200k
  // settle case: 1.6 % of the run), one pass over all particles per plane as long.
  constexpr std::size_t kMaskWalls = 32;
  constexpr Index kBlock = 512;
  const std::size_t masked = std::min(walls.size(), kMaskWalls);
  // Meshes, or walls past the masks, need the per-wall loop for each particle below.
  bool per_wall = walls.size() > kMaskWalls;
  for (std::size_t w = 0; w < masked; ++w) per_wall = per_wall || walls[w].shape == WallShape::Mesh;
  PageVector<Index>& near = list.scratch_count;  // (the pair list's build scratch, idle here)
  near.resize(n);
  Index* __restrict mask = near.data();
  const Real* __restrict xs = reinterpret_cast<const Real*>(x);
  const Real* __restrict rs = r;
  static_assert(sizeof(Vec3) == 3 * sizeof(Real));
  for (Index i0 = 0; i0 < n; i0 += kBlock) {
    const Index i1 = std::min(n, i0 + kBlock);
    std::fill(mask + i0, mask + i1, 0);
    for (std::size_t w = 0; w < masked; ++w) {
      const Wall& wall = walls[w];
      const Index bit = static_cast<Index>(std::uint32_t(1) << w);
      if (wall.shape == WallShape::Plane) {
        // The distance as Wall::closest computes it: (x - p) . n in Vec3::dot's order.
        const Real p0 = wall.point[0], p1 = wall.point[1], p2 = wall.point[2];
        const Real n0 = wall.normal[0], n1 = wall.normal[1], n2 = wall.normal[2];
        for (Index i = i0; i < i1; ++i) {
          const Real s =
              ((xs[3 * i] - p0) * n0 + (xs[3 * i + 1] - p1) * n1) + (xs[3 * i + 2] - p2) * n2;
          mask[i] |= -static_cast<Index>(s < rs[i] + skin) & bit;
        }
      } else if (wall.shape != WallShape::Mesh) {
        for (Index i = i0; i < i1; ++i) {
          WallContact c;
          if (wall.closest(x[i], c) && c.distance < r[i] + skin) mask[i] |= bit;
        }
      }
    }
  }
  list.first.resize(n + 1);
  list.partner.clear();
  std::vector<int> candidates;
  for (Index i = 0; i < n; ++i) {
    list.first[i] = static_cast<Index>(list.partner.size());
    if (!per_wall) {  // the set bits, in wall order
      for (auto m = static_cast<std::uint32_t>(near[i]); m != 0; m &= m - 1)
        list.partner.push_back(primitive_first[__builtin_ctz(m)]);
      continue;
    }
    const Real reach = r[i] + skin;
    for (std::size_t w = 0; w < walls.size(); ++w) {
      const Wall& wall = walls[w];
      if (wall.shape == WallShape::Mesh) {
        wall.mesh->candidates(x[i], candidates);
        std::sort(candidates.begin(), candidates.end());
        for (int t : candidates)
          if ((wall.mesh->closest(t, x[i]).point - x[i]).squaredNorm() < reach * reach)
            list.partner.push_back(primitive_first[w] + t);
      } else if (w < kMaskWalls) {
        if ((static_cast<std::uint32_t>(near[i]) >> w) & 1u)
          list.partner.push_back(primitive_first[w]);
      } else {
        WallContact c;
        if (wall.closest(x[i], c) && c.distance < reach) list.partner.push_back(primitive_first[w]);
      }
    }
  }
  list.first[n] = static_cast<Index>(list.partner.size());
  assign_growing(list.history, list.partner.size() * list.history_stride, 0.0);
  assign_growing<std::uint8_t>(list.touching, list.partner.size(), 0);
  index_rows(list);
}

}  // namespace grainscale
