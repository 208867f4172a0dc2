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
// Written over the lane type T (core/simd_pack.hpp): branches are selects.
#pragma once

#include <cmath>

#include "contact/contact_input.hpp"
#include "contact/tangential_models.hpp"
#include "core/simd_pack.hpp"

namespace grainscale {

struct RollingPair {
  Real friction;  // mu_r
  Real damping;   // eta_r
};

template <class T>
struct RollingContext {
  T normal_force;          // F_n (with damping)
  T normal_stiffness;      // k_n
  T tangential_stiffness;  // k_t
};

struct NoRolling {
  static constexpr const char* kName = "none";
  static constexpr int kHistorySize = 0;
  static constexpr bool kActive = false;
  static constexpr bool kSpring = false;
  static constexpr bool kInertia = false;  // reads ContactLanes::rolling_inertia
  template <class T>
  [[gnu::always_inline]] static LaneVec<T> evaluate(const Param<RollingPair, T>&,
                                                    const RollingContext<T>&,
                                                    const ContactLanes<T>&, LaneVec<T>&) {
    return LaneVec<T>::zero();
  }
};

template <class T>
[[gnu::always_inline]] inline LaneVec<T> rolling_velocity(const ContactLanes<T>& c) {
  return c.w_rel - dot(c.w_rel, c.normal) * c.normal;
}

struct CDTRolling {
  static constexpr const char* kName = "cdt";
  static constexpr int kHistorySize = 0;
  static constexpr bool kActive = true;
  static constexpr bool kSpring = false;
  static constexpr bool kInertia = false;
  template <class T>
  [[gnu::always_inline]] static LaneVec<T> evaluate(const Param<RollingPair, T>& p,
                                                    const RollingContext<T>& k,
                                                    const ContactLanes<T>& c, LaneVec<T>&) {
    const LaneVec<T> wr = rolling_velocity(c);
    const T w = sqrt_lanes(squared_norm(wr));
    const auto none = mask_or(w == 0.0, k.normal_force <= 0.0);
    const LaneVec<T> torque =
        ((-p.get(&RollingPair::friction)) * c.r_eff * k.normal_force / w) * wr;
    return select(none, LaneVec<T>::zero(), torque);
  }
};

template <bool kEPSD2>
struct SpringDashpotRolling {
  static constexpr const char* kName = kEPSD2 ? "epsd2" : "epsd";
  static constexpr int kHistorySize = 3;  // spring torque M_k (3-vector)
  static constexpr bool kActive = true;
  static constexpr bool kSpring = true;      // the history is a tangent-plane vector
  static constexpr bool kInertia = !kEPSD2;  // the damping
  template <class T>
  [[gnu::always_inline]] static LaneVec<T> evaluate(const Param<RollingPair, T>& p,
                                                    const RollingContext<T>& k,
                                                    const ContactLanes<T>& c, LaneVec<T>& spring) {
    const LaneVec<T> wr = rolling_velocity(c);
    const T mu = p.get(&RollingPair::friction);
    const T r2 = c.r_eff * c.r_eff;
    T kr;
    if constexpr (kEPSD2)
      kr = k.tangential_stiffness * r2;
    else
      kr = 2.25 * k.normal_stiffness * mu * mu * r2;
    spring = spring - (kr * c.dt) * wr;
    const T limit = mu * c.r_eff * abs_lanes(k.normal_force);
    const T m2 = squared_norm(spring);
    const auto plastic = m2 > limit * limit;  // fully mobilised: no damping
    if (any(plastic)) spring = select(plastic, spring * (limit / sqrt_lanes(m2)), spring);
    if constexpr (kEPSD2) {
      return spring;
    } else {
      const T eta = p.get(&RollingPair::damping);
      const auto undamped = mask_or(plastic, eta == 0.0);
      if (all(undamped)) return spring;
      const LaneVec<T> damped = spring - (eta * 2.0 * sqrt_lanes(c.rolling_inertia * kr)) * wr;
      return select(undamped, spring, damped);
    }
  }
};

using EPSDRolling = SpringDashpotRolling<false>;
using EPSD2Rolling = SpringDashpotRolling<true>;

}  // namespace grainscale
