#include "integrate/time_step.hpp"

#include <cmath>

#include "core/errors.hpp"
#include "core/hertz_impact.hpp"

namespace grainscale {

Real rayleigh_time(Real radius, Real density, Real youngs_modulus, Real poisson_ratio) {
  if (!(radius > 0)) throw_invalid("rayleigh_time.radius", "positive (m)", radius);
  const Real shear = youngs_modulus / (2 * (1 + poisson_ratio));
  return M_PI * radius * std::sqrt(density / shear) / (0.1631 * poisson_ratio + 0.8766);
}

Real hertz_contact_time(Real r_eff, Real m_eff, Real e_eff, Real v0) {
  if (!(v0 > 0)) throw_invalid("hertz_contact_time.impact_velocity", "positive (m/s)", v0);
  const Real delta_max = r_eff * std::pow(hertz_impact_number(m_eff, v0, e_eff, r_eff), 0.4);
  // 2 * integral_0^1 dx / sqrt(1 - x^(5/2)) = 2 * 1.471638 (CASES.md A1)
  return 2.943275 * delta_max / v0;
}

}  // namespace grainscale
