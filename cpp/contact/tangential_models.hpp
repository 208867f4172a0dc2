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
#pragma once

#include <algorithm>
#include <cmath>

#include "contact/contact_input.hpp"
#include "core/packed_math.hpp"

namespace grainscale {

enum class TangentialHistory { Total, Incremental };
enum class SpringRotation { Rescale, Project };

// Removes the normal component of a stored tangential vector and restores its magnitude.
[[gnu::always_inline]] inline void rotate_into_tangent_plane(Eigen::Map<Vec3>& s, const Vec3& n) {
  const Real sn = s.dot(n);
  if (sn == 0) return;
  const Real old2 = s.squaredNorm();
  s -= sn * n;
  const Real new2 = s.squaredNorm();
  if (new2 > 0) s *= std::sqrt(old2 / new2);
}

// Removes the normal component only (SpringRotation::Project).
[[gnu::always_inline]] inline void project_onto_tangent_plane(Eigen::Map<Vec3>& s, const Vec3& n) {
  const Real sn = s.dot(n);
  if (sn != 0) s -= sn * n;
}

// The same for two vectors of one contact (tangential and rolling spring), bit for bit as two
// calls of the above, with both rescale factors from one two-lane division and square root:
// they are the longest latency of a rolling contact.
[[gnu::always_inline]] inline void rotate_into_tangent_plane(Eigen::Map<Vec3>& a,
                                                             Eigen::Map<Vec3>& b, const Vec3& n) {
  const Real an = a.dot(n), bn = b.dot(n);
  if (an == 0 && bn == 0) return;
  const Real a_old2 = a.squaredNorm(), b_old2 = b.squaredNorm();
  const Vec3 at = a - an * n, bt = b - bn * n;
  const Real a_new2 = at.squaredNorm(), b_new2 = bt.squaredNorm();
  // A lane with new2 = 0 yields inf or NaN here and is not used.
  const RealPair scale = sqrt_ratio2(a_old2, a_new2, b_old2, b_new2);
  if (an != 0) a = a_new2 > 0 ? Vec3(at * scale.first) : at;
  if (bn != 0) b = b_new2 > 0 ? Vec3(bt * scale.second) : bt;
}

// Turns the stored spring(s) of a contact with its normal, as `how` says (the law's setting).
[[gnu::always_inline]] inline void follow_normal(SpringRotation how, Eigen::Map<Vec3>& s,
                                                 const Vec3& n) {
  if (how == SpringRotation::Rescale)
    rotate_into_tangent_plane(s, n);
  else
    project_onto_tangent_plane(s, n);
}
[[gnu::always_inline]] inline void follow_normal(SpringRotation how, Eigen::Map<Vec3>& a,
                                                 Eigen::Map<Vec3>& b, const Vec3& n) {
  if (how == SpringRotation::Rescale) {
    rotate_into_tangent_plane(a, b, n);
  } else {
    project_onto_tangent_plane(a, n);
    project_onto_tangent_plane(b, n);
  }
}

struct MindlinTangential {
  static constexpr int kHistorySize = 3;  // spring (3-vector)

  // Force on i. kt, gt: stiffness and damping; ft_max = mu max(F_n, 0). The spring in
  // `history` has been rotated into the current tangent plane.
  [[gnu::always_inline]] static Vec3 evaluate(TangentialHistory form, Real kt, Real gt, Real ft_max,
                                              const ContactInput& c, const Vec3& vt,
                                              Real* history) {
    Eigen::Map<Vec3> spring(history);
    const bool total = form == TangentialHistory::Total;
    Vec3 ft;
    if (total) {
      spring += vt * c.dt;
      ft = -kt * spring - gt * vt;
    } else {
      spring -= (kt * c.dt) * vt;
      ft = spring - gt * vt;
    }
    const Real ft2 = ft.squaredNorm();
    if (ft2 > ft_max * ft_max) {
      const Real s = spring.norm();
      if (s > 0) {
        const Vec3 dir = spring / s;
        ft = total ? Vec3(-ft_max * dir) : Vec3(ft_max * dir);
        spring = total ? Vec3((ft_max / kt) * dir) : ft;
      } else {
        ft *= ft_max / std::sqrt(ft2);
        spring = total ? Vec3(-ft / kt) : ft;
      }
    }
    return ft;
  }
};

}  // namespace grainscale
