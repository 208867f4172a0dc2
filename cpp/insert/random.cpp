#include "insert/random.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/errors.hpp"

namespace grainscale {

Real normal_cdf(Real x) { return 0.5 * std::erfc(-x * M_SQRT1_2); }

Real normal_quantile(Real p) {
  // P. J. Acklam (2003), relative error 1.15e-9, refined by one Halley step on erfc.
  static const Real a[] = {-3.969683028665376e+01, 2.209460984245205e+02,  -2.759285104469687e+02,
                           1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  static const Real b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                           6.680131188771972e+01, -1.328068155288572e+01};
  static const Real c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                           -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  static const Real d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                           3.754408661907416e+00};
  if (!(p > 0)) return -INFINITY;
  if (!(p < 1)) return INFINITY;
  const Real p_low = 0.02425;
  Real x;
  if (p < p_low) {
    const Real q = std::sqrt(-2 * std::log(p));
    x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  } else if (p <= 1 - p_low) {
    const Real q = p - 0.5;
    const Real r = q * q;
    x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
        (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
  } else {
    const Real q = std::sqrt(-2 * std::log1p(-p));
    x = -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  }
  const Real e = normal_cdf(x) - p;
  const Real u = e * std::sqrt(2 * M_PI) * std::exp(0.5 * x * x);
  return x - u / (1 + 0.5 * x * u);
}

Real truncated_standard_normal(Real alpha, Real beta, Real u) {
  // Invert where the cumulative probabilities are small (the lower tail), so that bounds far in
  // the upper tail keep their precision: reflect when the whole interval lies above the mean.
  if (alpha > 0) return -truncated_standard_normal(-beta, -alpha, 1 - u);
  const Real p_lo = normal_cdf(alpha), p_hi = normal_cdf(beta);
  const Real p = p_lo + u * (p_hi - p_lo);
  if (!(p > p_lo)) return alpha;
  return std::clamp(normal_quantile(p), alpha, beta);
}

std::string rng_state(const Rng& rng) {
  std::ostringstream out;
  out << rng;
  return out.str();
}

void set_rng_state(Rng& rng, const std::string& state) {
  std::istringstream in(state);
  Rng r;
  in >> r;
  if (in.fail()) throw_invalid("random engine state", "text written by rng_state()", "'...'");
  rng = r;
}

}  // namespace grainscale
