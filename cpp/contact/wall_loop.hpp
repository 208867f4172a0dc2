// The particle-wall force loop: the same contact law as particle pairs, with the wall as body j
// (R_j, m_j infinite; its own material or the rigid pseudo-material). Accumulates the force and
// torque (about the wall's origin) that the particles exert on each wall.
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

}  // namespace detail

template <class Law, bool kUpdate, bool kStats>
void accumulate_wall_forces(const Law& law, ParticleStore& ps, std::vector<Wall>& walls,
                            const WallPrimitives& prims, ContactList& list, Real dt,
                            ContactStats& stats) {
  constexpr int S = Law::kHistorySize;
  std::vector<detail::MeshTouch> touches;
  std::vector<char> counted;
  // The particles with wall entries are a thin, scattered subset (those near a wall), listed at
  // the build (list.rows); each one's data is requested kLead particles ahead, which overlaps
  // the cache misses with the force work.
  const std::vector<Index>& rows = list.rows;
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

    // One touching contact: entry k (its touch flag), history h, geometry g.
    auto apply = [&](Wall& wall, int w, Index k, const Real* h_in, const WallContact& g) {
      const Real overlap = ri - g.distance;
      const Vec3& nrm = g.normal;
      const Real ai = ri - 0.5 * overlap;
      const Vec3 vrel =
          ps.velocity[i] - ai * ps.angular_velocity[i].cross(nrm) - wall.surface_velocity(g.point);
      ContactInput c{nrm, overlap, ri, ps.mass[i], vrel, dt};
      if constexpr (Law::kRolling) {
        c.w_rel = ps.angular_velocity[i] - wall.angular_velocity;
        c.rolling_inertia = 1 / ps.inv_rolling_inertia[i];
      }
      const auto& pair = law.pair(ps.material[i], wall.law_material);
      Real* h = list.history.data() + static_cast<std::size_t>(k) * S;
      ContactOutput out;
      if constexpr (kUpdate) {
        if (h != h_in) std::copy(h_in, h_in + S, h);
        list.touching[k] = 1;
        out = law.force(pair, c, h);
      } else {
        std::array<Real, S> scratch;
        std::copy(h_in, h_in + S, scratch.begin());
        out = law.force(pair, c, scratch.data());
      }
      const Vec3& F = out.force;
      ps.force[i] += F;
      ps.torque[i] -= ai * nrm.cross(F);
      wall.force -= F;
      wall.torque -= (g.point - wall.origin).cross(F);
      if constexpr (Law::kRolling) {
        ps.torque[i] += out.rolling_torque;
        wall.torque -= out.rolling_torque;
      }
      if constexpr (kStats) {
        ++stats.contacts;
        stats.max_overlap_ratio = std::max(stats.max_overlap_ratio, overlap / ri);
        if (stats.record)
          stats.records.push_back({ps.id[i], -1 - GlobalId(w), overlap, nrm, F, i, -1});
      }
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
          apply(wall, w, k, list.history.data() + static_cast<std::size_t>(k) * S, g);
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
        apply(wall, w, m.entry, h, {m.hit.point, dist > 0 ? Vec3(diff / dist) : face_normal, dist});
      }
      for (Index m = k; m < end; ++m)
        if (counted[m - k] != 1) release(m);
      k = end;
    }
  }
}

}  // namespace grainscale
