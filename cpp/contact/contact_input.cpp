#include "contact/contact_input.hpp"

#include <cmath>

namespace grainscale {

Real restitution_beta(Real e) {
  if (e <= 0) return -1.0;
  const Real l = std::log(e);
  return l / std::sqrt(l * l + M_PI * M_PI);
}

}  // namespace grainscale
