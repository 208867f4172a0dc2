// The particle-wall force loop: the same contact law as particle pairs, with the wall as body j
// (R_j, m_j infinite; its own material or the rigid pseudo-material). Accumulates the force and
// torque (about the wall's origin) that the particles exert on each wall. The touching contacts
// are gathered in a batch, the law evaluated on packs of them and the contacts then applied in
// order (detail::WallBatch), so every sum is the one-contact-at-a-time loop's, bit for bit.
//
// Mesh walls: a sphere near a shared edge or vertex is close to several triangles, but touches
// the surface once. Per particle and mesh the touching triangles are resolved as follows:
// of coplanar triangles only the nearest hit counts (a flat patch has one closest point); an
// edge or vertex hit is dropped when a triangle containing it is strictly nearer; then
// every face contact counts; an edge contact counts unless the edge belongs to a triangle with
// a face contact, and touching the same edge through several triangles counts once; a vertex
// contact counts unless the vertex belongs to a counted face or edge, once per vertex. When the
// contact moves to another triangle (sliding across an edge) the new entry takes over the
// tangential and rolling history of the entry that stopped touching, so a triangulated plane
// behaves like the analytic one.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "contact/contact_input.hpp"
#include "contact/contact_stats.hpp"
#include "geometry/wall.hpp"
#include "neighbor/neighbor_list.hpp"
#include "state/particle_store.hpp"

namespace grainscale {

struct WallPrimitives {
  std::vector<int> wall;     // wall of each primitive
  std::vector<Index> first;  // first primitive of each wall
};

namespace detail {

struct MeshTouch {
  Index entry;
  int triangle;
  TriangleHit hit;
  bool counted = false;
  bool dropped = false;
  Vec3 normal = Vec3::Zero();  // of the triangle
  Real distance2 = 0;          // squared distance from the sphere centre to the hit
};

inline bool triangle_has(const std::array<int, 3>& t, int v) {
  return t[0] == v || t[1] == v || t[2] == v;
}

// Marks which of the touching triangles of one mesh count as contacts (rules above).
// `reach` is the particle radius: the coplanarity tolerance is relative to it (no absolute
// lengths, so exact scaling holds).
inline void resolve_mesh_touches(const TriangleMesh& mesh, const ContactList& list, const Vec3& x,
                                 Real reach, std::vector<MeshTouch>& touches) {
  // Entries that were touching keep their histories: prefer them among equals.
  auto better = [&](const MeshTouch& a, const MeshTouch& b) {
    return list.touching[a.entry] > list.touching[b.entry] ||
           (list.touching[a.entry] == list.touching[b.entry] && a.entry < b.entry);
  };
  // 1. Coplanar triangles form one planar patch whose closest point is unique: keep only the
  //    nearest hit of each plane (a sphere over a flat vertex or edge touches the floor once).
  for (MeshTouch& m : touches) {
    const auto& t = mesh.triangles[m.triangle];
    m.normal = (mesh.vertices[t[1]] - mesh.vertices[t[0]])
                   .cross(mesh.vertices[t[2]] - mesh.vertices[t[0]])
                   .normalized();
    m.distance2 = (x - m.hit.point).squaredNorm();
    m.dropped = false;
  }
  const Real tol = 1e-9;
  for (MeshTouch& m : touches)
    for (const MeshTouch& o : touches) {
      if (&o == &m || m.normal.cross(o.normal).norm() > tol ||
          std::abs(m.normal.dot(o.hit.point - m.hit.point)) > tol * reach)
        continue;
      if (o.distance2 < m.distance2 || (o.distance2 == m.distance2 && better(o, m))) {
        m.dropped = true;
        break;
      }
    }
  // 2. An edge or vertex touch is spurious when a triangle containing that edge or vertex is
  //    strictly nearer through another feature (the surface's closest point is elsewhere; e.g.
  //    a gently convex faceted patch touched near an apex).
  for (MeshTouch& m : touches) {
    if (m.dropped || m.hit.feature == 0) continue;
    for (const MeshTouch& o : touches) {
      if (&o == &m || !(o.distance2 < m.distance2)) continue;
      const auto& tri = mesh.triangles[o.triangle];
      const bool contains = m.hit.feature == 1
                                ? triangle_has(tri, m.hit.a) && triangle_has(tri, m.hit.b)
                                : triangle_has(tri, m.hit.a);
      if (contains) {
        m.dropped = true;
        break;
      }
    }
  }
  // 3. Faces count; edges and vertices of counted faces (and vertices of counted edges) are
  //    shadowed; one contact per edge or vertex.
  for (MeshTouch& m : touches) m.counted = !m.dropped && m.hit.feature == 0;
  for (int feature = 1; feature <= 2; ++feature) {
    for (MeshTouch& m : touches) {
      if (m.dropped || m.hit.feature != feature) continue;
      bool shadowed = false;
      for (const MeshTouch& o : touches) {
        if (!o.counted) continue;
        const auto& tri = mesh.triangles[o.triangle];
        if (o.hit.feature == 0)
          shadowed = feature == 1 ? triangle_has(tri, m.hit.a) && triangle_has(tri, m.hit.b)
                                  : triangle_has(tri, m.hit.a);
        else if (o.hit.feature == 1 && feature == 2)
          shadowed = o.hit.a == m.hit.a || o.hit.b == m.hit.a;
        else if (o.hit.feature == feature && o.hit.a == m.hit.a && o.hit.b == m.hit.b)
          shadowed = !better(m, o);
        if (shadowed) break;
      }
      if (shadowed) continue;
      // A better duplicate replaces an already counted one.
      for (MeshTouch& o : touches)
        if (o.counted && o.hit.feature == feature && o.hit.a == m.hit.a && o.hit.b == m.hit.b)
          o.counted = false;
      m.counted = true;
    }
  }
}

// Requests the cache lines that the wall loop reads and writes for particle i.
inline void prefetch_wall_row(const ParticleStore& ps, const ContactList& list, Index i, int S) {
  const Index k = list.first[i];
  __builtin_prefetch(ps.position.data() + i);
  __builtin_prefetch(ps.velocity.data() + i);
  __builtin_prefetch(ps.angular_velocity.data() + i);
  __builtin_prefetch(ps.force.data() + i, 1);
  __builtin_prefetch(ps.torque.data() + i, 1);
  __builtin_prefetch(ps.radius.data() + i);
  __builtin_prefetch(ps.mass.data() + i);
  __builtin_prefetch(ps.material.data() + i);
  __builtin_prefetch(list.partner.data() + k);
  __builtin_prefetch(list.touching.data() + k, 1);
  __builtin_prefetch(list.history.data() + static_cast<std::size_t>(k) * S, 1);
}

// Touching particle-wall contacts, gathered so that the law runs on packs of kPackLanes contacts
// (core/simd_pack.hpp) and then replayed in order: the forces and the sums on particles and
// walls are the bits of a one-contact-at-a-time loop. A contact's history is copied in when it
// is gathered (a mesh contact may take over the history of an entry released right after) and
// written back, with its touch flag, at the replay.
template <class Law>
struct WallBatch {
  static constexpr int kCapacity = 64;  // a multiple of every lane width
  static constexpr int S = Law::kHistorySize;
  using Column = Real[kCapacity];
  alignas(64) Column nx, ny, nz, overlap, r_eff, m_eff, vx, vy, vz, wx, wy, wz, rolling_inertia;
  alignas(64) Column fx, fy, fz, mx, my, mz;  // results: force and rolling torque on i
  alignas(64) Real history[S > 0 ? S : 1][kCapacity];
  const typename Law::Pair* pair[kCapacity];
  Index i[kCapacity], entry[kCapacity];
  int wall[kCapacity];
  Vec3 lever[kCapacity];  // contact point - wall origin
  Real arm[kCapacity];    // r_i - overlap / 2
  int count = 0;

  void pad(int end) {
    for (Real* column :
         {nx, ny, nz, overlap, r_eff, m_eff, vx, vy, vz, wx, wy, wz, rolling_inertia})
      std::fill(column + count, column + end, column[count - 1]);
    for (int s = 0; s < S; ++s)
      std::fill(history[s] + count, history[s] + end, history[s][count - 1]);
    std::fill(pair + count, pair + end, pair[count - 1]);
  }
};

// The law on lanes [b, b + kPackLanes) of a wall batch; the histories are updated in the batch.
template <class Law, class Batch>
[[gnu::always_inline]] inline void evaluate_wall_pack(const Law& law, Batch& batch, int b,
                                                      Real dt) {
  using T = LaneReal;
  constexpr int S = Law::kHistorySize;
  auto in = [&](const Real* column) { return load_lanes<T>(column + b); };
  const ContactLanes<T> c{{in(batch.nx), in(batch.ny), in(batch.nz)},
                          in(batch.overlap),
                          in(batch.r_eff),
                          in(batch.m_eff),
                          {in(batch.vx), in(batch.vy), in(batch.vz)},
                          dt,
                          {in(batch.wx), in(batch.wy), in(batch.wz)},
                          in(batch.rolling_inertia)};
  T h[S > 0 ? S : 1];
  for (int s = 0; s < S; ++s) h[s] = in(batch.history[s]);
  ContactLanesOutput<T> out;
  if constexpr (std::is_same_v<T, Real>)
    out = law.force_lanes(Param<typename Law::Pair, Real>(*batch.pair[b]), c, h);
  else
    out = law.force_lanes(Param<typename Law::Pair, T>::of(batch.pair + b), c, h);
  for (int s = 0; s < S; ++s) store_lanes(batch.history[s] + b, h[s]);
  store_lanes(batch.fx + b, out.force.x);
  store_lanes(batch.fy + b, out.force.y);
  store_lanes(batch.fz + b, out.force.z);
  store_lanes(batch.mx + b, out.rolling_torque.x);
  store_lanes(batch.my + b, out.rolling_torque.y);
  store_lanes(batch.mz + b, out.rolling_torque.z);
}

}  // namespace detail

template <class Law, bool kUpdate, bool kStats>
void accumulate_wall_forces(const Law& law, ParticleStore& ps, std::vector<Wall>& walls,
                            const WallPrimitives& prims, ContactList& list, Real dt,
                            ContactStats& stats) {
  constexpr int S = Law::kHistorySize;
  constexpr int W = kPackLanes;
  using Batch = detail::WallBatch<Law>;
  Batch batch;
  // Evaluates the batch in packs and applies its contacts in the order they were found.
  auto flush = [&]() {
    const int count = batch.count;
    if (count == 0) return;
    const int end = (count + W - 1) / W * W;
    if (end > count) batch.pad(end);
    for (int b = 0; b < end; b += W) detail::evaluate_wall_pack(law, batch, b, dt);
    for (int q = 0; q < count; ++q) {
      const Index i = batch.i[q];
      const int w = batch.wall[q];
      Wall& wall = walls[w];
      if constexpr (kUpdate) {
        const Index k = batch.entry[q];
        for (int s = 0; s < S; ++s)
          list.history[static_cast<std::size_t>(k) * S + s] = batch.history[s][q];
        list.touching[k] = 1;
      }
      const Vec3 F(batch.fx[q], batch.fy[q], batch.fz[q]);
      const Vec3 nrm(batch.nx[q], batch.ny[q], batch.nz[q]);
      ps.force[i] += F;
      ps.torque[i] -= batch.arm[q] * nrm.cross(F);
      wall.force -= F;
      wall.torque -= batch.lever[q].cross(F);
      if constexpr (Law::kRolling) {
        const Vec3 M(batch.mx[q], batch.my[q], batch.mz[q]);
        ps.torque[i] += M;
        wall.torque -= M;
      }
      if constexpr (kStats) {
        const Real overlap = batch.overlap[q];
        ++stats.contacts;
        stats.max_overlap_ratio = std::max(stats.max_overlap_ratio, overlap / batch.r_eff[q]);
        if (stats.record)
          stats.records.push_back({ps.id[i], -1 - GlobalId(w), overlap, nrm, F, i, -1});
      }
    }
    batch.count = 0;
  };
  std::vector<detail::MeshTouch> touches;
  std::vector<char> counted;
  // The particles with wall entries are a thin, scattered subset (those near a wall), listed at
  // the build (list.rows); each one's data is requested kLead particles ahead, which overlaps
  // the cache misses with the force work.
  const PageVector<Index>& rows = list.rows;
  const Index n_rows = static_cast<Index>(rows.size());
  constexpr Index kLead = 4;
  for (Index r = 0; r < std::min(kLead, n_rows); ++r)
    detail::prefetch_wall_row(ps, list, rows[r], S);
  for (Index r = 0; r < n_rows; ++r) {
    if (r + kLead < n_rows) detail::prefetch_wall_row(ps, list, rows[r + kLead], S);
    const Index i = rows[r];
    const Index b = list.first[i], e = list.first[i + 1];
    const Vec3 xi = ps.position[i];
    const Real ri = ps.radius[i];

    // One touching contact into the batch: entry k, its history h (a mesh contact may take
    // over another entry's), geometry g.
    auto push = [&](const Wall& wall, int w, Index k, const Real* h, const WallContact& g) {
      if (batch.count == Batch::kCapacity) flush();
      const int q = batch.count++;
      const Real overlap = ri - g.distance;
      const Vec3& nrm = g.normal;
      const Real ai = ri - 0.5 * overlap;
      const Vec3 vrel =
          ps.velocity[i] - ai * ps.angular_velocity[i].cross(nrm) - wall.surface_velocity(g.point);
      Vec3 w_rel = Vec3::Zero();
      Real rolling_inertia = 0;
      if constexpr (Law::kRolling) w_rel = ps.angular_velocity[i] - wall.angular_velocity;
      if constexpr (Law::kRollingInertia) rolling_inertia = 1 / ps.inv_rolling_inertia[i];
      batch.nx[q] = nrm[0];
      batch.ny[q] = nrm[1];
      batch.nz[q] = nrm[2];
      batch.overlap[q] = overlap;
      batch.r_eff[q] = ri;
      batch.m_eff[q] = ps.mass[i];
      batch.vx[q] = vrel[0];
      batch.vy[q] = vrel[1];
      batch.vz[q] = vrel[2];
      batch.wx[q] = w_rel[0];
      batch.wy[q] = w_rel[1];
      batch.wz[q] = w_rel[2];
      batch.rolling_inertia[q] = rolling_inertia;
      for (int s = 0; s < S; ++s) batch.history[s][q] = h[s];
      batch.pair[q] = &law.pair(ps.material[i], wall.law_material);
      batch.i[q] = i;
      batch.entry[q] = k;
      batch.wall[q] = w;
      batch.lever[q] = g.point - wall.origin;
      batch.arm[q] = ai;
    };
    auto release = [&](Index k) {
      if (kUpdate && list.touching[k]) {
        Real* h = list.history.data() + static_cast<std::size_t>(k) * S;
        std::fill(h, h + S, Real(0));
        list.touching[k] = 0;
      }
    };

    Index k = b;
    while (k < e) {
      const int w = prims.wall[list.partner[k]];
      Wall& wall = walls[w];
      if (wall.shape != WallShape::Mesh) {
        WallContact g;
        if (wall.closest(xi, g) && g.distance < ri)
          push(wall, w, k, list.history.data() + static_cast<std::size_t>(k) * S, g);
        else
          release(k);
        ++k;
        continue;
      }
      // All entries of this mesh for particle i.
      Index end = k;
      while (end < e && prims.wall[list.partner[end]] == w) ++end;
      const TriangleMesh& mesh = *wall.mesh;
      touches.clear();
      for (Index m = k; m < end; ++m) {
        const int t = list.partner[m] - prims.first[w];
        const TriangleHit hit = mesh.closest(t, xi);
        if ((xi - hit.point).squaredNorm() < ri * ri) touches.push_back({m, t, hit});
      }
      detail::resolve_mesh_touches(mesh, list, xi, ri, touches);
      counted.assign(end - k, 0);
      for (const detail::MeshTouch& m : touches)
        if (m.counted) counted[m.entry - k] = 1;
      for (const detail::MeshTouch& m : touches) {
        if (!m.counted) continue;
        // A new contact inherits the history of an entry of this mesh that stopped touching.
        const Real* h = list.history.data() + static_cast<std::size_t>(m.entry) * S;
        if (!list.touching[m.entry])
          for (Index d = k; d < end; ++d)
            if (list.touching[d] && !counted[d - k]) {
              h = list.history.data() + static_cast<std::size_t>(d) * S;
              counted[d - k] = 2;  // donor: its history moved
              break;
            }
        const Vec3 diff = xi - m.hit.point;
        const Real dist = diff.norm();
        const auto& tri = mesh.triangles[m.triangle];
        const Vec3 face_normal = (mesh.vertices[tri[1]] - mesh.vertices[tri[0]])
                                     .cross(mesh.vertices[tri[2]] - mesh.vertices[tri[0]])
                                     .normalized();
        push(wall, w, m.entry, h, {m.hit.point, dist > 0 ? Vec3(diff / dist) : face_normal, dist});
      }
      for (Index m = k; m < end; ++m)
        if (counted[m - k] != 1) release(m);
      k = end;
    }
  }
  flush();
}

}  // namespace grainscale
