// Two independent square roots of quotients in one two-lane division and square root (the
// longest latencies of a contact); bit for bit the same results as the scalar operations (IEEE
// division and square root are correctly rounded in every lane).
#pragma once

#include <cmath>

#include "core/types.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace grainscale {

struct RealPair {
  Real first, second;
};

// sqrt(a0 / b0) and sqrt(a1 / b1).
[[gnu::always_inline]] inline RealPair sqrt_ratio2(Real a0, Real b0, Real a1, Real b1) {
#if defined(__SSE2__)
  alignas(16) Real r[2];
  _mm_store_pd(r, _mm_sqrt_pd(_mm_div_pd(_mm_set_pd(a1, a0), _mm_set_pd(b1, b0))));
  return {r[0], r[1]};
#else
  return {std::sqrt(a0 / b0), std::sqrt(a1 / b1)};
#endif
}

}  // namespace grainscale
