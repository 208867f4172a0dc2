// Rolling-resistance sub-models (usable with every normal model). w_r is the tangential part
// of the relative angular velocity omega_i - omega_j; the torque returned acts on i (j gets its
// negative). mu_r = rolling friction, eta_r = rolling damping ratio, R* effective radius.
//
// NoRolling:  none.
// CDT (constant directional torque; Zhou et al. 1999 / LIGGGHTS rolling_friction cdt):
//   M = -mu_r R* max(F_n, 0) w_r / |w_r|. It cannot hold a sphere at rest and oscillates
//   around zero rolling velocity — the defect EPSD removes (CASES.md A6).
// EPSD (elastic–plastic spring–dashpot; Ai, Chen, Rotter & Ooi 2011, Powder Technol. 206:269;
//   LIGGGHTS rolling_model_epsd.h): k_r = 2.25 k_n mu_r^2 R*^2,
//   M_k += -k_r w_r dt (history, rotated into the tangent plane by the law together with the
//   tangential spring), |M_k| <= mu_r R* |F_n|;
//   M_d = -eta_r 2 sqrt(I_r k_r) w_r only while M_k is below the limit.
// EPSD2 (LIGGGHTS epsd2): as EPSD with k_r = k_t R*^2 and no damping.
#pragma once

#include <cmath>

#include "contact/contact_input.hpp"
#include "contact/tangential_models.hpp"

namespace grainscale {

struct RollingPair {
  Real friction;  // mu_r
  Real damping;   // eta_r
};

struct RollingContext {
  Real normal_force;          // F_n (with damping)
  Real normal_stiffness;      // k_n
  Real tangential_stiffness;  // k_t
};

struct NoRolling {
  static constexpr const char* kName = "none";
  static constexpr int kHistorySize = 0;
  static constexpr bool kActive = false;
  static constexpr bool kSpring = false;
  [[gnu::always_inline]] static Vec3 evaluate(const RollingPair&, const RollingContext&,
                                              const ContactInput&, Real*) {
    return Vec3::Zero();
  }
};

inline Vec3 rolling_velocity(const ContactInput& c) {
  return c.w_rel - c.w_rel.dot(c.normal) * c.normal;
}

struct CDTRolling {
  static constexpr const char* kName = "cdt";
  static constexpr int kHistorySize = 0;
  static constexpr bool kActive = true;
  static constexpr bool kSpring = false;
  [[gnu::always_inline]] static Vec3 evaluate(const RollingPair& p, const RollingContext& k,
                                              const ContactInput& c, Real*) {
    const Vec3 wr = rolling_velocity(c);
    const Real w = wr.norm();
    if (w == 0 || k.normal_force <= 0) return Vec3::Zero();
    return (-p.friction * c.r_eff * k.normal_force / w) * wr;
  }
};

template <bool kEPSD2>
struct SpringDashpotRolling {
  static constexpr const char* kName = kEPSD2 ? "epsd2" : "epsd";
  static constexpr int kHistorySize = 3;  // spring torque M_k (3-vector)
  static constexpr bool kActive = true;
  static constexpr bool kSpring = true;  // the history is a tangent-plane vector
  [[gnu::always_inline]] static Vec3 evaluate(const RollingPair& p, const RollingContext& k,
                                              const ContactInput& c, Real* history) {
    const Vec3 wr = rolling_velocity(c);
    const Real r2 = c.r_eff * c.r_eff;
    const Real kr = kEPSD2 ? k.tangential_stiffness * r2
                           : 2.25 * k.normal_stiffness * p.friction * p.friction * r2;
    Eigen::Map<Vec3> spring(history);
    spring -= (kr * c.dt) * wr;
    const Real limit = p.friction * c.r_eff * std::abs(k.normal_force);
    const Real m2 = spring.squaredNorm();  // the square root only when the limit is reached
    if (m2 > limit * limit) {
      spring *= limit / std::sqrt(m2);  // fully mobilised: plastic, no damping
      return spring;
    }
    if (kEPSD2 || p.damping == 0) return spring;
    return spring - (p.damping * 2 * std::sqrt(c.rolling_inertia * kr)) * wr;
  }
};

using EPSDRolling = SpringDashpotRolling<false>;
using EPSD2Rolling = SpringDashpotRolling<true>;

}  // namespace grainscale
