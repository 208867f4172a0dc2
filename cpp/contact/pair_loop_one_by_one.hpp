// The particle-particle force loop one contact at a time: the law's scalar form (T = Real) on
// each touching entry as the scan meets it. pair_loop.hpp takes it in builds without SIMD packs
// (GRAINSCALE_SIMD=OFF): with one lane, batching contacts only adds a round trip through the
// batch. The same forces, torques and histories as the batched loop, bit for bit
// (tests/cpp/test_contact_lanes.cpp).
// Torque arm: contact radius r - overlap/2 (as LIGGGHTS).
#pragma once

#include <algorithm>
#include <array>

#include "contact/contact_input.hpp"
#include "contact/contact_stats.hpp"
#include "neighbor/neighbor_list.hpp"
#include "state/particle_store.hpp"

namespace grainscale {

// kUpdate = false evaluates forces without advancing the history (set-up evaluations must
// not advance the tangential springs). kStats fills `stats`.
// flatten: everything the law calls is inlined. Left to its heuristics, GCC stops inlining
// small Eigen expressions in the larger laws (EEPA, EPSD), and each call costs more than it does.
template <class Law, bool kUpdate, bool kStats>
[[gnu::flatten]] void accumulate_pair_forces_one_by_one(const Law& law, ParticleStore& ps,
                                                        ContactList& list, Real dt,
                                                        ContactStats& stats) {
  constexpr int S = Law::kHistorySize;
  const Index n = ps.n_owned();
  const Vec3* x = ps.position.data();
  const Vec3* v = ps.velocity.data();
  const Vec3* w = ps.angular_velocity.data();
  const Real* r = ps.radius.data();
  const Real* im = ps.inv_mass.data();
  const Real* irl = ps.inv_rolling_inertia.data();
  const std::int32_t* mat = ps.material.data();
  Vec3* f = ps.force.data();
  Vec3* t = ps.torque.data();
  const Index* partner = list.partner.data();
  Real* hist = list.history.data();
  for (Index i = 0; i < n; ++i) {
    const Index b = list.first[i], e = list.first[i + 1];
    if (b == e) continue;
    const Vec3 xi = x[i], vi = v[i], wi = w[i];
    const Real ri = r[i], imi = im[i];
    const int mi = mat[i];
    Vec3 fi = Vec3::Zero(), ti = Vec3::Zero();
    for (Index k = b; k < e; ++k) {
      const Index j = partner[k];
      Real* h = hist + static_cast<std::size_t>(k) * S;
      const Vec3 d = xi - x[j];
      const Real rj = r[j];
      const Real rsum = ri + rj;
      const Real d2 = d.squaredNorm();
      if (d2 >= rsum * rsum) {
        if (kUpdate && list.touching[k]) {
          std::fill(h, h + S, Real(0));
          list.touching[k] = 0;
        }
        continue;
      }
      const Real dist = std::sqrt(d2);
      const Real overlap = rsum - dist;
      const PairMeans<Real> means =
          Law::kRollingInertia
              ? pair_means<true>(from_eigen(d), dist, ri, rj, rsum, imi + im[j], irl[i] + irl[j])
              : pair_means<false>(from_eigen(d), dist, ri, rj, rsum, imi + im[j]);
      const Vec3 nrm = to_eigen(means.normal);
      const Real ai = ri - 0.5 * overlap, aj = rj - 0.5 * overlap;
      const Vec3 vrel = vi - v[j] - (ai * wi + aj * w[j]).cross(nrm);
      ContactInput c{nrm, overlap, means.r_eff, means.m_eff, vrel, dt};
      if constexpr (Law::kRolling) {
        c.w_rel = wi - w[j];
      }
      if constexpr (Law::kRollingInertia) c.rolling_inertia = means.rolling_inertia;
      ContactOutput out;
      if constexpr (kUpdate) {
        list.touching[k] = 1;
        out = law.force(law.pair(mi, mat[j]), c, h);
      } else {
        std::array<Real, S> scratch;
        std::copy(h, h + S, scratch.begin());
        out = law.force(law.pair(mi, mat[j]), c, scratch.data());
      }
      const Vec3& F = out.force;
      const Vec3 nxf = nrm.cross(F);
      fi += F;
      ti -= ai * nxf;
      f[j] -= F;
      t[j] -= aj * nxf;
      if constexpr (Law::kRolling) {
        ti += out.rolling_torque;
        t[j] -= out.rolling_torque;
      }
      if constexpr (kStats) {
        ++stats.contacts;
        stats.max_overlap_ratio = std::max(stats.max_overlap_ratio, overlap / std::min(ri, rj));
        if (stats.record) stats.records.push_back({ps.id[i], ps.id[j], overlap, nrm, F, i, j});
      }
    }
    f[i] += fi;
    t[i] += ti;
  }
}

}  // namespace grainscale
