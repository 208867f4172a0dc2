#include "insert/size_distribution.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/errors.hpp"

namespace grainscale {

namespace {

bool positive_finite(Real v) { return v > 0 && std::isfinite(v); }

void check_positive(const std::string& owner, const char* name, Real v) {
  if (!positive_finite(v)) throw_invalid(owner + "." + name, "positive and finite (m)", v);
}

void check_bounds(const std::string& owner, Real min, Real max) {
  check_positive(owner, "min", min);
  check_positive(owner, "max", max);
  if (!(max >= min)) {
    std::ostringstream c;
    c << ">= " << owner << ".min = " << shortest(min) << " (m)";
    throw_invalid(owner + ".max", c.str(), max);
  }
}

}  // namespace

SizeDistribution SizeDistribution::monodisperse(Real radius) {
  check_positive("Monodisperse", "radius", radius);
  SizeDistribution d;
  d.kind_ = Kind::Monodisperse;
  d.p1_ = d.min_ = d.max_ = radius;
  return d;
}

SizeDistribution SizeDistribution::uniform(Real min, Real max) {
  check_bounds("Uniform", min, max);
  SizeDistribution d;
  d.kind_ = Kind::Uniform;
  d.p1_ = d.min_ = min;
  d.p2_ = d.max_ = max;
  return d;
}

SizeDistribution SizeDistribution::normal(Real mean, Real std, Real min, Real max) {
  check_positive("Normal", "mean", mean);
  if (!(std >= 0) || !std::isfinite(std))
    throw_invalid("Normal.std", "non-negative and finite (m)", std);
  check_bounds("Normal", min, max);
  if (std > 0 && normal_cdf((max - mean) / std) - normal_cdf((min - mean) / std) <= 0)
    throw_invalid("Normal.min", "such that [min, max] holds some probability", min);
  SizeDistribution d;
  d.kind_ = Kind::Normal;
  d.p1_ = mean;
  d.p2_ = std;
  d.min_ = min;
  d.max_ = max;
  if (std == 0) {
    if (!(mean >= min && mean <= max))
      throw_invalid("Normal.mean", "in [min, max] when std = 0", mean);
    d.min_ = d.max_ = mean;
  }
  return d;
}

SizeDistribution SizeDistribution::lognormal(Real median, Real sigma, Real min, Real max) {
  check_positive("LogNormal", "median", median);
  if (!(sigma >= 0) || !std::isfinite(sigma))
    throw_invalid("LogNormal.sigma", "non-negative and finite (of ln r)", sigma);
  check_bounds("LogNormal", min, max);
  const Real mu = std::log(median);
  if (sigma > 0 &&
      normal_cdf((std::log(max) - mu) / sigma) - normal_cdf((std::log(min) - mu) / sigma) <= 0)
    throw_invalid("LogNormal.min", "such that [min, max] holds some probability", min);
  SizeDistribution d;
  d.kind_ = Kind::LogNormal;
  d.p1_ = median;
  d.p2_ = sigma;
  d.min_ = min;
  d.max_ = max;
  if (sigma == 0) {
    if (!(median >= min && median <= max))
      throw_invalid("LogNormal.median", "in [min, max] when sigma = 0", median);
    d.min_ = d.max_ = median;
  }
  return d;
}

SizeDistribution SizeDistribution::discrete(const std::vector<Real>& radii,
                                            const std::vector<Real>& weights, bool by_mass) {
  if (radii.empty()) throw_invalid("Discrete.radii", "non-empty", 0);
  if (weights.size() != radii.size())
    throw_invalid("Discrete.weights",
                  "one weight per radius (" + std::to_string(radii.size()) + ")", weights.size());
  SizeDistribution d;
  d.kind_ = Kind::Discrete;
  d.min_ = INFINITY;
  d.max_ = 0;
  Real total = 0;
  for (std::size_t k = 0; k < radii.size(); ++k) {
    check_positive("Discrete", "radii", radii[k]);
    if (!(weights[k] >= 0) || !std::isfinite(weights[k]))
      throw_invalid("Discrete.weights", "non-negative and finite", weights[k]);
    const Real w = by_mass ? weights[k] / (radii[k] * radii[k] * radii[k]) : weights[k];
    total += w;
    d.radii_.push_back(radii[k]);
    d.cumulative_.push_back(total);
    if (weights[k] > 0) {
      d.min_ = std::min(d.min_, radii[k]);
      d.max_ = std::max(d.max_, radii[k]);
      d.last_radius_ = radii[k];
    }
  }
  if (!(total > 0)) throw_invalid("Discrete.weights", "not all zero", total);
  for (Real& c : d.cumulative_) c /= total;
  return d;
}

std::string SizeDistribution::name() const {
  switch (kind_) {
    case Kind::Monodisperse:
      return "Monodisperse";
    case Kind::Uniform:
      return "Uniform";
    case Kind::Normal:
      return "Normal";
    case Kind::LogNormal:
      return "LogNormal";
    case Kind::Discrete:
      return "Discrete";
  }
  return "?";
}

Real SizeDistribution::sample(Rng& rng) const {
  const Real u = uniform01(rng);
  switch (kind_) {
    case Kind::Monodisperse:
      return p1_;
    case Kind::Uniform:
      return std::min(p1_ + u * (p2_ - p1_), p2_);
    case Kind::Normal:
      if (p2_ == 0) return min_;
      return std::clamp(
          p1_ + p2_ * truncated_standard_normal((min_ - p1_) / p2_, (max_ - p1_) / p2_, u), min_,
          max_);
    case Kind::LogNormal: {
      if (p2_ == 0) return min_;
      // r = median exp(sigma z) with bounds from min / median, max / median: ratios, so that
      // radii scale exactly with the distribution (bit for bit when x 2^k).
      const Real z =
          truncated_standard_normal(std::log(min_ / p1_) / p2_, std::log(max_ / p1_) / p2_, u);
      return std::clamp(p1_ * std::exp(p2_ * z), min_, max_);
    }
    case Kind::Discrete: {
      // First class whose cumulative probability exceeds u (classes of zero weight never win).
      const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), u);
      if (it == cumulative_.end()) return last_radius_;  // u above the rounded total
      return radii_[it - cumulative_.begin()];
    }
  }
  return p1_;
}

}  // namespace grainscale
