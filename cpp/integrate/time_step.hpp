// Time-step helpers (DESIGN.md 2.2, CASES.md A1).
#pragma once

#include "core/types.hpp"

namespace grainscale {

// Rayleigh time t_R = pi r sqrt(rho / G) / (0.1631 nu + 0.8766), G = E / (2 (1 + nu)).
Real rayleigh_time(Real radius, Real density, Real youngs_modulus, Real poisson_ratio);

// Elastic Hertz contact duration t_c = 2.943275 delta_max / v0 with
// delta_max = (15 m* v0^2 / (16 E* sqrt(R*)))^(2/5) (CASES.md A1).
Real hertz_contact_time(Real effective_radius, Real effective_mass, Real effective_youngs,
                        Real impact_velocity);

// Largest time step accepted without forcing, as a fraction of the smallest Rayleigh time.
constexpr Real kMaxRayleighFraction = 0.3;

}  // namespace grainscale
