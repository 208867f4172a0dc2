// Damping sub-models: a dashpot proportional to sqrt(stiffness * m*), with the ratio set by the
// restitution coefficient through beta = ln e / sqrt(ln^2 e + pi^2) (< 0):
//   gamma = kFactor * |beta| * sqrt(k * m*)
// HertzDamping (LIGGGHTS hertz, Tsuji-type): kFactor = 2 sqrt(5/6) on the contact stiffness
//   S = dF/d(delta); with a Hertz spring this gives exactly the prescribed e (CASES.md A3).
// ViscousDamping (linear spring–dashpot; Thakur et al. 2016 Eq. 4 and 9):
//   kFactor = 2, i.e. gamma = 2 zeta sqrt(k m*) = sqrt(4 m* k / (1 + (pi / ln e)^2)).
#pragma once

#include <cmath>

#include "core/types.hpp"

namespace grainscale {

struct HertzDamping {
  static constexpr const char* kName = "hertz";
  static Real factor() { return 2 * std::sqrt(5.0 / 6.0); }
};

struct ViscousDamping {
  static constexpr const char* kName = "viscous";
  static Real factor() { return 2; }
};

}  // namespace grainscale
