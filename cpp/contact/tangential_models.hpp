// Tangential sub-model: Mindlin-type spring with history and Coulomb limit (DESIGN.md 2.4).
//   total form:        xi += v_t dt,         F_t = -k_t xi - g_t v_t   (LIGGGHTS "history")
//   incremental form:  F_s += -k_t v_t dt,   F_t = F_s - g_t v_t       (Thornton et al. 2011;
//                                                                      Thakur et al. 2016 Eq. 6-7)
//   Coulomb: |F_t| <= mu max(F_n, 0). When exceeded F_t = -mu F_n+ xi/|xi| (no damping while
//   sliding) and the stored spring is truncated to match. A tensile (damping-dominated) normal
//   force carries no friction, so the tangential impulse never exceeds mu times the compressive
//   normal impulse.
// The stored spring (xi or F_s) follows the contact: each step, before evaluate(), the law
// removes its normal component (rotate_into_tangent_plane) and, by default, restores its
// magnitude, so a pair turning rigidly keeps its spring (as LAMMPS pair granular does).
// SpringRotation::Project only removes the normal component, as LIGGGHTS' tangential history
// model does (tangential_model_history.h): the spring then shrinks by cos(theta) when the normal
// turns by theta in a step, a second-order loss that saves a division and a square root.
// Written over the lane type T (core/simd_pack.hpp): branches are selects.
#pragma once

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "contact/contact_input.hpp"
#include "core/simd_pack.hpp"

namespace grainscale {

enum class TangentialHistory { Total, Incremental };
enum class SpringRotation { Rescale, Project };

// Removes the normal component of a stored tangential vector and restores its magnitude.
template <class T>
[[gnu::always_inline]] inline void rotate_into_tangent_plane(LaneVec<T>& s, const LaneVec<T>& n) {
  const T sn = dot(s, n);
  if constexpr (std::is_same_v<T, Real>)
    if (sn == 0) return;  // one contact: skip the division and root (a new contact has no spring)
  const T old2 = squared_norm(s);
  const LaneVec<T> t = s - sn * n;
  const T new2 = squared_norm(t);
  // A lane with new2 = 0 yields inf or NaN in the scaled vector and is not used.
  const LaneVec<T> scaled = t * sqrt_lanes(old2 / new2);
  s = select(sn == 0.0, s, select(new2 > 0.0, scaled, t));
}

// Removes the normal component only (SpringRotation::Project).
template <class T>
[[gnu::always_inline]] inline void project_onto_tangent_plane(LaneVec<T>& s, const LaneVec<T>& n) {
  const T sn = dot(s, n);
  s = select(sn != 0.0, s - sn * n, s);
}

// Turns the stored spring of a contact with its normal, as `how` says (the law's setting).
template <class T>
[[gnu::always_inline]] inline void follow_normal(SpringRotation how, LaneVec<T>& s,
                                                 const LaneVec<T>& n) {
  if (how == SpringRotation::Rescale)
    rotate_into_tangent_plane(s, n);
  else
    project_onto_tangent_plane(s, n);
}

struct MindlinTangential {
  static constexpr int kHistorySize = 3;  // spring (3-vector)

  // Force on i. kt, gt: stiffness and damping; ft_max = mu max(F_n, 0). The spring has been
  // rotated into the current tangent plane; it is updated here.
  template <class T>
  [[gnu::always_inline]] static LaneVec<T> evaluate(TangentialHistory form, T kt, T gt, T ft_max,
                                                    const ContactLanes<T>& c, const LaneVec<T>& vt,
                                                    LaneVec<T>& spring) {
    const bool total = form == TangentialHistory::Total;
    LaneVec<T> ft;
    if (total) {
      spring = spring + vt * c.dt;
      ft = (-kt) * spring - gt * vt;
    } else {
      spring = spring - (kt * c.dt) * vt;
      ft = spring - gt * vt;
    }
    const T ft2 = squared_norm(ft);
    const auto sliding = ft2 > ft_max * ft_max;
    if (!any(sliding)) return ft;
    // Coulomb limit: along the spring, or (no spring) along the force. Reciprocals, not
    // divisions of vectors: 3 divisions instead of 8 (contact_input.hpp, pair_means).
    const T s = sqrt_lanes(squared_norm(spring));
    const auto along_spring = s > 0.0;
    const LaneVec<T> dir = spring * (1.0 / s);  // inf or NaN where s = 0: not used
    const T inv_kt = total ? 1.0 / kt : splat<T>(0);
    const LaneVec<T> ft_spring = total ? (-ft_max) * dir : ft_max * dir;
    const LaneVec<T> spring_spring = total ? (ft_max * inv_kt) * dir : ft_spring;
    const LaneVec<T> ft_force = ft * (ft_max / sqrt_lanes(ft2));
    const LaneVec<T> spring_force = total ? (-ft_force) * inv_kt : ft_force;
    spring = select(sliding, select(along_spring, spring_spring, spring_force), spring);
    return select(sliding, select(along_spring, ft_spring, ft_force), ft);
  }
};

}  // namespace grainscale
