// Portable random numbers for insertion: a seeded std::mt19937_64 (its output sequence is fixed by
// the standard) turned into variates by code of our own, because the std:: distributions may
// differ between standard libraries. Same seed, same particles, on every platform.
#pragma once

#include <cstdint>
#include <random>
#include <string>

#include "core/types.hpp"

namespace grainscale {

using Rng = std::mt19937_64;

// Uniform in [0, 1) with 53 random bits.
inline Real uniform01(Rng& rng) { return static_cast<Real>(rng() >> 11) * 0x1.0p-53; }

// Standard normal cumulative distribution Phi(x).
Real normal_cdf(Real x);
// Inverse of Phi for p in (0, 1) (Acklam's rational approximation + one Halley step: full
// double precision).
Real normal_quantile(Real p);
// Standard normal truncated to [alpha, beta], by inversion of u in [0, 1) (one uniform per
// variate, so the stream of random numbers consumed does not depend on the parameters).
Real truncated_standard_normal(Real alpha, Real beta, Real u);

// Engine state as text (operator<< of the standard engine) and back; for checkpoints.
std::string rng_state(const Rng& rng);
void set_rng_state(Rng& rng, const std::string& state);

}  // namespace grainscale
