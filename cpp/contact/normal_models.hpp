// Normal sub-models: the spring (elastic or hysteretic) part of the normal force and the
// stiffnesses the other sub-models build on. Compression positive; d = overlap.
//
// HertzNormal (Hertz 1882; DESIGN.md 2.4; LIGGGHTS normal_model_hertz.h):
//   F = k_n d,  k_n = 4/3 E* sqrt(R* d),  damping stiffness S_n = 2 E* sqrt(R* d),
//   k_t = 8 G* sqrt(R* d) (Mindlin).
// LinearNormal (Hooke spring–dashpot; LIGGGHTS normal_model_hooke.h for the derived k_n):
//   F = k_n d with k_n given per material pair, or
//   k_n = 16/15 sqrt(R*) E* (15 m* v_c^2 / (16 sqrt(R*) E*))^(1/5) (the linear spring with the
//   same maximum overlap as Hertz at impact speed v_c), evaluated as 16/15 E* R* u^(1/5) with
//   u = 15 m* v_c^2 / (16 E* R*^3) (core/hertz_impact.hpp: exactly scale invariant); k_t given
//   or 2/7 k_n.
// EEPANormal (Thakur, Morrissey, Sun, Chen & Ooi 2014, Granular Matter 16:383; Thakur, Ooi &
//   Ahmadian 2016, Powder Technol. 293:130, Eq. 2), exponent n in {1, 1.5}:
//     loading            F = f0 + k1 d^n                 if k2 (d^n - dp^n) >= k1 d^n
//     unloading/reload.  F = f0 + k2 (d^n - dp^n)        if k1 d^n > k2 (d^n - dp^n) > -k_adh d^chi
//     adhesive           F = f0 - k_adh d^chi            otherwise,
//   with the plastic overlap dp^n = (1 - k1/k2) d_max^n (history: d_max, the largest overlap).
//   Pull-off definition used here: the constant-parameter form of the paper — f0 and k_adh
//   are given (per material pair), not derived from a surface energy; the pull-off force is
//   then the minimum of F, reached where the unloading line meets the adhesive branch.
//   k1 <= 0 means k1 = 2 E* R* (n = 1, so that k1 ~ R) or 4/3 E* sqrt(R*) (n = 1.5).
//   Stiffness seen by damping and the tangential spring: the virgin loading slope
//   k_load = n k1 d^(n-1) (= k1 for n = 1); k_t = 2/7 k_load (Thakur et al. 2016).
#pragma once

#include <algorithm>
#include <cmath>

#include "contact/contact_input.hpp"
#include "contact/interaction.hpp"
#include "core/hertz_impact.hpp"
#include "core/simd_pack.hpp"
#include "state/material_table.hpp"

namespace grainscale {

template <class T>
struct NormalState {
  T spring;                // elastic/hysteretic normal force (without damping)
  T stiffness;             // k_n used by rolling models (EPSD)
  T damping_stiffness;     // stiffness the normal dashpot is built on
  T tangential_stiffness;  // k_t
  // sqrt(k_t / damping_stiffness), for models where it is a constant of the pair
  // (kFixedTangentialRatio): the tangential dashpot then costs no square root of its own.
  T tangential_root_ratio;
};

struct HertzNormal {
  static constexpr const char* kName = "hertz";
  static constexpr int kHistorySize = 0;
  static constexpr bool kFixedTangentialRatio = true;  // k_t / S_n = 8 G* / (2 E*)
  struct Pair {
    Real effective_youngs, effective_shear;
    Real tangential_root_ratio;  // sqrt(4 G* / E*)
  };
  static Pair make_pair(const PairModuli& m, const Interaction&) {
    return {m.effective_youngs, m.effective_shear,
            std::sqrt(4.0 * m.effective_shear / m.effective_youngs)};
  }
  template <class T>
  [[gnu::always_inline]] static NormalState<T> evaluate(const Param<Pair, T>& p,
                                                        const ContactLanes<T>& c, T*) {
    const T youngs = p.get(&Pair::effective_youngs);
    const T sqrt_rd = sqrt_lanes(c.r_eff * c.overlap);
    const T kn = (4.0 / 3.0) * youngs * sqrt_rd;
    return {kn * c.overlap, kn, 2.0 * youngs * sqrt_rd,
            8.0 * p.get(&Pair::effective_shear) * sqrt_rd, p.get(&Pair::tangential_root_ratio)};
  }
};

struct LinearNormal {
  static constexpr const char* kName = "linear";
  // The derived k_n (a power per evaluation) is constant over a contact (R*, m* are): it is
  // computed when the contact starts and kept in the history.
  static constexpr int kHistorySize = 1;
  static constexpr bool kFixedTangentialRatio = false;  // k_t given, k_n derived per contact
  struct Pair {
    Real normal_stiffness;      // > 0: given; else derived per contact
    Real tangential_ratio;      // k_t / k_n when k_t is not given
    Real tangential_stiffness;  // > 0: given
    Real effective_youngs;
    Real characteristic_velocity;
  };
  static Pair make_pair(const PairModuli& m, const Interaction& in) {
    return {in.normal_stiffness, 2.0 / 7.0, in.tangential_stiffness, m.effective_youngs,
            in.characteristic_velocity};
  }
  static Real derived_stiffness(Real m_eff, Real v_c, Real youngs, Real r_eff) {
    const Real u = hertz_impact_number(m_eff, v_c, youngs, r_eff);
    return (16.0 / 15.0) * youngs * r_eff * std::pow(u, 0.2);
  }
  template <class T>
  [[gnu::always_inline]] static NormalState<T> evaluate(const Param<Pair, T>& p,
                                                        const ContactLanes<T>& c, T* history) {
    const T given = p.get(&Pair::normal_stiffness);
    const auto is_given = given > 0;
    const T stored = history[0];
    const auto derive = mask_and(mask_not(is_given), stored == 0);  // a contact's first step
    T derived = stored;
    if (any(derive))
      derived =
          select(derive,
                 per_lane(derive, derived_stiffness, c.m_eff, p.get(&Pair::characteristic_velocity),
                          p.get(&Pair::effective_youngs), c.r_eff),
                 stored);
    history[0] = select(is_given, stored, derived);
    const T kn = select(is_given, given, derived);
    const T kt_given = p.get(&Pair::tangential_stiffness);
    const T kt = select(kt_given > 0, kt_given, p.get(&Pair::tangential_ratio) * kn);
    return {kn * c.overlap, kn, kn, kt, splat<T>(0)};
  }
};

struct EEPANormal {
  static constexpr const char* kName = "eepa";
  static constexpr int kHistorySize = 1;               // d_max (scalar)
  static constexpr bool kFixedTangentialRatio = true;  // k_t / k = 2/7
  struct Pair {
    Real exponent;            // n
    Real loading_stiffness;   // k1 (> 0 given; else derived per contact)
    Real unloading_ratio;     // k2 / k1 >= 1
    Real plastic_fraction;    // 1 - k1 / k2, of the pair (not a division per contact)
    Real adhesive_stiffness;  // k_adh
    Real pull_off_force;      // f0
    Real adhesion_exponent;   // chi
    Real effective_youngs;
  };
  static Pair make_pair(const PairModuli& m, const Interaction& in) {
    return {in.eepa_exponent,      in.loading_stiffness,
            in.unloading_ratio,    1.0 - 1.0 / in.unloading_ratio,
            in.adhesive_stiffness, in.pull_off_force,
            in.adhesion_exponent,  m.effective_youngs};
  }
  // x^n (x >= 0): exact forms for n = 1, 1.5 and 0.5 (n - 1 of the common n = 1.5, in the
  // stiffness: per-lane std::pow there made EEPA with n = 1.5 cost 1.6-1.8 x Hertz-Mindlin per
  // contact), std::pow (per lane) otherwise. sqrt is correctly rounded; pow(x, 0.5) agrees
  // with it to within an ulp.
  template <class T>
  [[gnu::always_inline]] static T power(T x, T n) {
    const auto one = n == 1.0;
    if (all(one)) return x;
    const auto half = n == 0.5;
    const T root = sqrt_lanes(x);
    T r = select(one, x, select(half, root, x * root));
    const auto other = mask_not(mask_or(mask_or(one, half), n == 1.5));
    if (any(other))
      r = select(other, per_lane(other, [](Real a, Real b) { return std::pow(a, b); }, x, n), r);
    return r;
  }
  template <class T>
  [[gnu::always_inline]] static NormalState<T> evaluate(const Param<Pair, T>& p,
                                                        const ContactLanes<T>& c, T* history) {
    const T n = p.get(&Pair::exponent);
    const auto linear = n == 1.0;
    T k1 = p.get(&Pair::loading_stiffness);
    const auto derive = mask_not(k1 > 0);
    if (any(derive)) {
      const T youngs = p.get(&Pair::effective_youngs);
      k1 = select(
          derive,
          select(linear, 2.0 * youngs * c.r_eff, (4.0 / 3.0) * youngs * sqrt_lanes(c.r_eff)), k1);
    }
    const T k2 = p.get(&Pair::unloading_ratio) * k1;
    const T d_max = history[0];
    const T d = c.overlap;
    const T dn = power(d, n);
    const T f_load = k1 * dn;
    // Virgin loading is decided on the overlap, not on rounded branch forces.
    const auto loading = d >= d_max;
    const T dpn = p.get(&Pair::plastic_fraction) * power(d_max, n);
    const T f_unload = k2 * (dn - dpn);
    const T f_adh = -p.get(&Pair::adhesive_stiffness) * power(d, p.get(&Pair::adhesion_exponent));
    T f = select(f_unload >= f_load, f_load, select(f_unload > f_adh, f_unload, f_adh));
    f = select(loading, f_load, f);
    history[0] = select(loading, d, d_max);
    T k_load = k1;
    if (!all(linear)) k_load = select(linear, k1, n * k1 * power(d, n - 1.0));
    constexpr Real kRootTwoSevenths = 0.53452248382484876937;  // sqrt(2/7)
    return {p.get(&Pair::pull_off_force) + f, k_load, k_load, (2.0 / 7.0) * k_load,
            splat<T>(kRootTwoSevenths)};
  }
};

}  // namespace grainscale
