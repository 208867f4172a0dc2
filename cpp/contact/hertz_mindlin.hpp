// Hertz–Mindlin contact with nonlinear damping and tangential spring history.
//
// Equations (DESIGN.md 2.4; LIGGGHTS normal_model_hertz.h / tangential_model_history.h):
//   S_n = 2 E* sqrt(R* d),  S_t = 8 G* sqrt(R* d),  k_n = 4/3 E* sqrt(R* d),  k_t = S_t
//   beta = ln e / sqrt(ln^2 e + pi^2),  g_n = -2 sqrt(5/6) beta sqrt(S_n m*),
//   g_t = -2 sqrt(5/6) beta sqrt(S_t m*)
//   F_n = k_n d + g_n d'            (d' = overlap rate; optional clamp F_n >= 0: limit_force)
//   total form:       xi += v_t dt,  F_t = -k_t xi - g_t v_t
//   incremental form: F_s += -k_t v_t dt,  F_t = F_s - g_t v_t   (Thornton et al. 2011)
//   Coulomb: |F_t| <= mu max(F_n, 0); when exceeded F_t = -mu F_n+ xi/|xi| (no damping while
//   sliding) and the stored spring is truncated to match.
// The stored spring (xi or F_s) is kept in the current tangent plane every step: its normal
// component is removed and its magnitude restored (the contact rotates, the spring goes with it).
// With tension allowed this damping gives exactly the prescribed restitution (CASES.md A3).
#pragma once

#include <cmath>
#include <vector>

#include "contact/contact_input.hpp"
#include "state/material_table.hpp"

namespace grainscale {

enum class TangentialHistory { Total, Incremental };

struct HertzMindlinSettings {
  Real restitution = 0.5;
  Real friction = 0.5;
  bool limit_force = false;
  bool tangential_damping = true;
  TangentialHistory history = TangentialHistory::Total;
};

class HertzMindlin {
 public:
  static constexpr int kHistorySize = 3;  // tangential spring (3-vector, flips with i<->j)

  struct Pair {
    Real effective_youngs;
    Real effective_shear;
    Real damping_factor;  // -2 sqrt(5/6) beta >= 0
    Real friction;
  };

  explicit HertzMindlin(const HertzMindlinSettings& settings);
  const HertzMindlinSettings& settings() const { return settings_; }
  // Builds the per-material-pair table; index rigid_index() of `materials` is the rigid wall.
  void prepare(const MaterialTable& materials);
  const Pair& pair(int mi, int mj) const { return pairs_[mi * stride_ + mj]; }

  // Force on body i; `history` points at kHistorySize values owned by this contact.
  [[gnu::always_inline]] inline Vec3 force(const Pair& p, const ContactInput& c,
                                           Real* history) const;

 private:
  HertzMindlinSettings settings_;
  std::vector<Pair> pairs_;
  int stride_ = 0;
};

// Removes the normal component of a stored tangential vector and restores its magnitude.
inline void rotate_into_tangent_plane(Eigen::Map<Vec3>& s, const Vec3& n) {
  const Real sn = s.dot(n);
  if (sn == 0) return;
  const Real old2 = s.squaredNorm();
  s -= sn * n;
  const Real new2 = s.squaredNorm();
  if (new2 > 0) s *= std::sqrt(old2 / new2);
}

inline Vec3 HertzMindlin::force(const Pair& p, const ContactInput& c, Real* history) const {
  const Vec3& n = c.normal;
  const Real sqrt_rd = std::sqrt(c.r_eff * c.overlap);
  const Real sn = 2 * p.effective_youngs * sqrt_rd;
  const Real kt = 8 * p.effective_shear * sqrt_rd;
  const Real kn = (4.0 / 3.0) * p.effective_youngs * sqrt_rd;
  const Real vn = c.v_rel.dot(n);  // < 0 while approaching: overlap rate is -vn
  Real fn = kn * c.overlap - p.damping_factor * std::sqrt(sn * c.m_eff) * vn;
  if (settings_.limit_force && fn < 0) fn = 0;

  const Vec3 vt = c.v_rel - vn * n;
  const Real gt = settings_.tangential_damping ? p.damping_factor * std::sqrt(kt * c.m_eff) : 0;
  Eigen::Map<Vec3> spring(history);
  rotate_into_tangent_plane(spring, n);
  const bool total = settings_.history == TangentialHistory::Total;
  Vec3 ft;
  if (total) {
    spring += vt * c.dt;
    ft = -kt * spring - gt * vt;
  } else {
    spring -= (kt * c.dt) * vt;
    ft = spring - gt * vt;
  }
  const Real ft_max = p.friction * std::max<Real>(fn, 0);
  const Real ft2 = ft.squaredNorm();
  if (ft2 > ft_max * ft_max) {
    const Real s = spring.norm();
    if (s > 0) {
      // Sliding: force along the spring, no damping; spring truncated to the Coulomb limit.
      const Vec3 dir = spring / s;
      ft = total ? Vec3(-ft_max * dir) : Vec3(ft_max * dir);
      spring = total ? Vec3((ft_max / kt) * dir) : ft;
    } else {
      ft *= ft_max / std::sqrt(ft2);
      spring = total ? Vec3(-ft / kt) : ft;
    }
  }
  return fn * n + ft;
}

}  // namespace grainscale
