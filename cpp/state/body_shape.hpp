// Mass and moment of inertia of one particle: a solid sphere in 3-D, a disc of unit thickness
// (1 m) in the 2-D mode (DESIGN.md 2.1): m = rho (4/3) pi r^3, I = (2/5) m r^2 (sphere);
// m = rho pi r^2 x 1 m, I = (1/2) m r^2 (disc about its axis).
#pragma once

#include <cmath>

#include "core/types.hpp"

namespace grainscale {

inline Real particle_mass(Real density, Real radius, int dimension) {
  return dimension == 2 ? density * M_PI * radius * radius
                        : density * (4.0 / 3.0) * M_PI * radius * radius * radius;
}

inline Real particle_inertia(Real mass, Real radius, int dimension) {
  return (dimension == 2 ? 0.5 : 0.4) * mass * radius * radius;
}

}  // namespace grainscale
