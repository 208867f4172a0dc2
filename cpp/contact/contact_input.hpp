// What a contact law sees of one contact: geometry and kinematics at the contact point.
// Conventions (DESIGN.md 2.4): compression positive, n is the unit normal from body j to body i,
// v_rel is the velocity of i's contact point relative to j's. A wall is body j with R_j, m_j
// infinite, so r_eff = r_i and m_eff = m_i.
#pragma once

#include "core/simd_pack.hpp"
#include "core/types.hpp"

namespace grainscale {

struct ContactInput {
  Vec3 normal;
  Real overlap;  // > 0 while touching
  Real r_eff;    // R* = r_i r_j / (r_i + r_j)
  Real m_eff;    // m* = m_i m_j / (m_i + m_j)
  Vec3 v_rel;
  Real dt;
  // Filled only for laws with a rolling model (Law::kRolling):
  Vec3 w_rel = Vec3::Zero();  // omega_i - omega_j
  Real rolling_inertia = 0;   // I_r = [1/(I_i + m_i r_i^2) + 1/(I_j + m_j r_j^2)]^-1
};

// What a law returns: the force on i (j gets -force) and the rolling-resistance torque on i
// (j gets -torque); the torque of the tangential force about the centres is added by the loops.
struct ContactOutput {
  Vec3 force;
  Vec3 rolling_torque;
};

// The same for the laws' lane form (core/simd_pack.hpp): one contact (T = Real) or a pack.
template <class T>
struct ContactLanes {
  LaneVec<T> normal;
  T overlap, r_eff, m_eff;
  LaneVec<T> v_rel;
  Real dt;
  LaneVec<T> w_rel;  // rolling laws only
  T rolling_inertia;
};

template <class T>
struct ContactLanesOutput {
  LaneVec<T> force;
  LaneVec<T> rolling_torque;
};

// The unit normal n (from j to i), R*, m* and, with kInertia, the rolling inertia I_r of a
// particle pair: d = x_i - x_j, dist = |d|, the radii, rsum = r_i + r_j, inv_mass_sum =
// 1/m_i + 1/m_j and inv_rolling_sum = 1/I_i' + 1/I_j' (ContactInput::rolling_inertia). One
// contact (T = Real) or a pack; both pair loops take it, so that they give the same bits.
// Multiplications by reciprocals instead of divisions: a division of a pack costs what as many
// scalar ones cost (the divider is not as wide as the pack), and in the Hertz-Mindlin pair loop
// the divisions were the bottleneck (bench_pair_loop, bench/README.md). R*, m* and I_r share
// one: q = 1 / (rsum inv_mass_sum [inv_rolling_sum]), then R* = r_i r_j inv_mass_sum [...] q,
// m* = rsum [inv_rolling_sum] q, I_r = rsum inv_mass_sum q (all factors positive and far from
// overflow for any grain size).
template <class T>
struct PairMeans {
  LaneVec<T> normal;
  T r_eff, m_eff, rolling_inertia;
};
template <bool kInertia, class T>
[[gnu::always_inline]] inline PairMeans<T> pair_means(const LaneVec<T>& d, T dist, T ri, T rj,
                                                      T rsum, T inv_mass_sum,
                                                      T inv_rolling_sum = T{}) {
  const auto apart = dist > 0.0;
  const T inv_dist = 1.0 / dist;  // inf for coincident centres: not used
  // Coincident centres have no normal; pick +z so that they are pushed apart, not NaN.
  const LaneVec<T> n{select(apart, d.x * inv_dist, splat<T>(0)),
                     select(apart, d.y * inv_dist, splat<T>(0)),
                     select(apart, d.z * inv_dist, splat<T>(1))};
  const T rm = rsum * inv_mass_sum;
  if constexpr (kInertia) {
    const T q = 1.0 / (rm * inv_rolling_sum);
    return {n, ri * rj * inv_mass_sum * inv_rolling_sum * q, rsum * inv_rolling_sum * q, rm * q};
  } else {
    const T q = 1.0 / rm;
    return {n, ri * rj * inv_mass_sum * q, rsum * q, T{}};
  }
}

// Damping ratio factor beta = ln e / sqrt(ln^2 e + pi^2) (< 0), with beta(0) = -1.
Real restitution_beta(Real restitution);

}  // namespace grainscale
