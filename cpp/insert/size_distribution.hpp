// Particle size distributions (by number: the probability that a sampled particle has a radius in
// [r, r + dr]). Python declares them (grainscale.dist); sampling happens here, from a seeded
// engine, so that every insertion is reproducible and checkpointable.
//
//   Monodisperse(radius)                r = radius
//   Uniform(min, max)                   r ~ U[min, max]
//   Normal(mean, std, min, max)         r ~ N(mean, std^2) truncated to [min, max]
//   LogNormal(median, sigma, min, max)  ln r ~ N(ln median, sigma^2) truncated to [ln min, ln max]
//   Discrete(radii, weights)            r = radii[k] with probability proportional to the number
//                                       weights (mass fractions are converted: w_n ~ w_m / r^3)
//
// Each variate uses exactly one uniform number (inversion), so the random stream consumed is the
// same for every distribution.
#pragma once

#include <string>
#include <vector>

#include "core/types.hpp"
#include "insert/random.hpp"

namespace grainscale {

class SizeDistribution {
 public:
  enum class Kind { Monodisperse, Uniform, Normal, LogNormal, Discrete };

  // Named constructors validate their arguments; messages name the Python parameter, e.g.
  // "Uniform.min must be positive (m), got -1".
  static SizeDistribution monodisperse(Real radius);
  static SizeDistribution uniform(Real min, Real max);
  static SizeDistribution normal(Real mean, Real std, Real min, Real max);
  static SizeDistribution lognormal(Real median, Real sigma, Real min, Real max);
  // by_mass: weights are mass fractions (else number fractions); they need not sum to 1.
  static SizeDistribution discrete(const std::vector<Real>& radii, const std::vector<Real>& weights,
                                   bool by_mass);

  Kind kind() const { return kind_; }
  std::string name() const;
  Real sample(Rng& rng) const;
  // Support [min_radius, max_radius] (m).
  Real min_radius() const { return min_; }
  Real max_radius() const { return max_; }

 private:
  Kind kind_ = Kind::Monodisperse;
  Real p1_ = 0, p2_ = 0;  // radius | min, max | mean, std | median, sigma
  Real min_ = 0, max_ = 0;
  std::vector<Real> radii_, cumulative_;  // Discrete: radii and cumulative number probability
  Real last_radius_ = 0;                  // Discrete: last radius of non-zero weight
};

}  // namespace grainscale
