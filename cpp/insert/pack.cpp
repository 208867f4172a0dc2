#include "insert/pack.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>

#include "core/errors.hpp"

namespace grainscale {

namespace {
Real sphere_volume(Real r) { return (4.0 / 3.0) * M_PI * r * r * r; }
}  // namespace

std::vector<Real> pack_radii(const PackSpec& spec, Rng& rng) {
  std::vector<Real> radii;
  if (spec.count >= 0) {
    if (spec.count > 100'000'000) throw_invalid("Pack.count", "at most 1e8", spec.count);
    radii.reserve(spec.count);
    for (std::int64_t k = 0; k < spec.count; ++k) radii.push_back(spec.radius.sample(rng));
  } else {
    const Real target = spec.volume_fraction * spec.region.volume();
    const Real r_mean = 0.5 * (spec.radius.min_radius() + spec.radius.max_radius());
    if (target / sphere_volume(spec.radius.min_radius()) > 1e8 &&
        target / sphere_volume(r_mean) > 1e8)
      throw_invalid("Pack.volume_fraction", "a target of at most about 1e8 particles",
                    spec.volume_fraction);
    Real total = 0;
    // Stop at the sample that would take the total further from the target than it is.
    for (;;) {
      const Real r = spec.radius.sample(rng);
      const Real v = sphere_volume(r);
      if (total + 0.5 * v > target) break;
      radii.push_back(r);
      total += v;
    }
  }
  std::stable_sort(radii.begin(), radii.end(), std::greater<Real>());
  return radii;
}

Placement place_in_region(const PackSpec& spec, const std::vector<Real>& radii, OccupancyGrid& grid,
                          Rng& rng) {
  Placement out;
  out.position.reserve(radii.size());
  out.radius.reserve(radii.size());
  Real placed_volume = 0;
  for (std::size_t k = 0; k < radii.size(); ++k) {
    const Real r = radii[k];
    if (!spec.region.fits(r)) {
      std::ostringstream msg;
      msg << "Pack: a sphere of radius " << shortest(r) << " m does not fit inside the region";
      throw std::runtime_error(msg.str());
    }
    bool ok = false;
    for (int attempt = 0; attempt < spec.max_attempts && !ok; ++attempt) {
      const Vec3 x = spec.region.sample(rng, r);
      if (!grid.overlaps(x, r)) {
        grid.add(x, r);
        out.position.push_back(x);
        out.radius.push_back(r);
        placed_volume += sphere_volume(r);
        ok = true;
      }
    }
    if (!ok) {
      Real requested = 0;
      for (Real q : radii) requested += sphere_volume(q);
      const Real v = spec.region.volume();
      std::ostringstream msg;
      msg.precision(3);
      msg << "Pack placed only " << k << " of " << radii.size() << " particles: particle " << k + 1
          << " (radius " << shortest(r) << " m) found no free position in " << spec.max_attempts
          << " attempts; the region's volume fraction reached " << placed_volume / v
          << " of the requested " << requested / v
          << ". Nothing was inserted. Random sequential addition jams near 0.38 for equal "
             "spheres (less with particles already inside): lower count/volume_fraction, "
             "enlarge the region, or insert in stages and let the particles settle.";
      throw std::runtime_error(msg.str());
    }
  }
  return out;
}

}  // namespace grainscale
