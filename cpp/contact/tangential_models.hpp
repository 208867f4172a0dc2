// Tangential sub-model: Mindlin-type spring with history and Coulomb limit (DESIGN.md 2.4).
//   total form:        xi += v_t dt,         F_t = -k_t xi - g_t v_t   (LIGGGHTS "history")
//   incremental form:  F_s += -k_t v_t dt,   F_t = F_s - g_t v_t       (Thornton et al. 2011;
//                                                                      Thakur et al. 2016 Eq. 6-7)
//   Coulomb: |F_t| <= mu max(F_n, 0). When exceeded F_t = -mu F_n+ xi/|xi| (no damping while
//   sliding) and the stored spring is truncated to match. A tensile (damping-dominated) normal
//   force carries no friction, so the tangential impulse never exceeds mu times the compressive
//   normal impulse.
// The stored spring (xi or F_s) follows the contact: each step its normal component is removed
// and its magnitude restored.
#pragma once

#include <algorithm>
#include <cmath>

#include "contact/contact_input.hpp"

namespace grainscale {

enum class TangentialHistory { Total, Incremental };

// Removes the normal component of a stored tangential vector and restores its magnitude.
inline void rotate_into_tangent_plane(Eigen::Map<Vec3>& s, const Vec3& n) {
  const Real sn = s.dot(n);
  if (sn == 0) return;
  const Real old2 = s.squaredNorm();
  s -= sn * n;
  const Real new2 = s.squaredNorm();
  if (new2 > 0) s *= std::sqrt(old2 / new2);
}

struct MindlinTangential {
  static constexpr int kHistorySize = 3;  // spring (3-vector)

  // Force on i. kt, gt: stiffness and damping; ft_max = mu max(F_n, 0).
  [[gnu::always_inline]] static Vec3 evaluate(TangentialHistory form, Real kt, Real gt, Real ft_max,
                                              const ContactInput& c, const Vec3& vt,
                                              Real* history) {
    Eigen::Map<Vec3> spring(history);
    rotate_into_tangent_plane(spring, c.normal);
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
