// The particle-wall force loop: the same contact law as particle pairs, with the wall as body j
// (R_j, m_j infinite; its own material or the rigid pseudo-material). Accumulates the force and
// torque (about the wall's reference point) that the particles exert on each wall.
#pragma once

#include <algorithm>
#include <array>

#include "contact/contact_input.hpp"
#include "contact/contact_stats.hpp"
#include "geometry/plane_wall.hpp"
#include "neighbor/neighbor_list.hpp"
#include "state/particle_store.hpp"

namespace grainscale {

template <class Law, bool kUpdate, bool kStats>
void accumulate_wall_forces(const Law& law, ParticleStore& ps, std::vector<PlaneWall>& walls,
                            ContactList& list, Real dt, ContactStats& stats) {
  constexpr int S = Law::kHistorySize;
  const Index n = ps.n_owned();
  for (Index i = 0; i < n; ++i) {
    const Index b = list.first[i], e = list.first[i + 1];
    if (b == e) continue;
    const Vec3 xi = ps.position[i];
    const Real ri = ps.radius[i];
    for (Index k = b; k < e; ++k) {
      PlaneWall& wall = walls[list.partner[k]];
      Real* h = list.history.data() + static_cast<std::size_t>(k) * S;
      const WallContactGeometry g = wall.closest(xi);
      const Real overlap = ri - g.distance;
      if (overlap <= 0) {
        if (kUpdate && list.touching[k]) {
          std::fill(h, h + S, Real(0));
          list.touching[k] = 0;
        }
        continue;
      }
      const Vec3& nrm = g.normal;
      const Real ai = ri - 0.5 * overlap;
      const Vec3 vrel = ps.velocity[i] - ai * ps.angular_velocity[i].cross(nrm) - wall.velocity;
      ContactInput c{nrm, overlap, ri, ps.mass[i], vrel, dt};
      if constexpr (Law::kRolling) {
        c.w_rel = ps.angular_velocity[i];  // walls do not spin (yet)
        c.rolling_inertia = 1 / ps.inv_inertia[i] + ps.mass[i] * ri * ri;
      }
      const auto& pair = law.pair(ps.material[i], wall.law_material);
      ContactOutput out;
      if constexpr (kUpdate) {
        list.touching[k] = 1;
        out = law.force(pair, c, h);
      } else {
        std::array<Real, S> scratch;
        std::copy(h, h + S, scratch.begin());
        out = law.force(pair, c, scratch.data());
      }
      const Vec3& F = out.force;
      ps.force[i] += F;
      ps.torque[i] -= ai * nrm.cross(F);
      if constexpr (Law::kRolling) {
        ps.torque[i] += out.rolling_torque;
        wall.torque -= out.rolling_torque;
      }
      const Vec3 contact_point = xi - g.distance * nrm;
      wall.force -= F;
      wall.torque -= (contact_point - wall.point).cross(F);
      if constexpr (kStats) {
        ++stats.contacts;
        stats.max_overlap_ratio = std::max(stats.max_overlap_ratio, overlap / ri);
        if (stats.record)
          stats.records.push_back(
              {ps.id[i], -1 - static_cast<GlobalId>(list.partner[k]), overlap, nrm, F});
      }
    }
  }
}

}  // namespace grainscale
