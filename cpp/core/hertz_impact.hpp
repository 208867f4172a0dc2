// The dimensionless Hertz impact number u = 15 m* v^2 / (16 E* R*^3) (Johnson 1985, Contact
// Mechanics, sec. 11.4). The maximum overlap of an elastic Hertz impact at speed v is
// delta_max = R* u^(2/5), and the linear spring with that same maximum overlap is
// k = 16/15 E* R* u^(1/5) (LIGGGHTS normal_model_hooke). Written with R*^3 instead of the usual
// sqrt(R*) so that it is exactly scale invariant: under lengths x h, times x h, density x 1
// (Feng & Owen 2014) u is unchanged, and for h a power of two bit for bit.
#pragma once

#include "core/types.hpp"

namespace grainscale {

inline Real hertz_impact_number(Real m_eff, Real v, Real e_eff, Real r_eff) {
  return 15 * m_eff * v * v / (16 * e_eff * (r_eff * r_eff * r_eff));
}

}  // namespace grainscale
