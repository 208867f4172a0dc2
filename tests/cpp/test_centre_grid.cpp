// CentreGrid::nearest checked against brute force (prints every failed check, returns non-zero
// if any failed): random centres, queries inside and just outside the box, reaches from a
// fraction of a cell to many cells, cells from a tenth of the reach to more than it, and a
// periodic axis (the nearest image counts).
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "expect.hpp"
#include "insert/centre_grid.hpp"

namespace gs = grainscale;
using gs::Real;
using gs::Vec3;

namespace {

std::mt19937_64 g_rng(2024);
Real uniform(Real a, Real b) { return std::uniform_real_distribution<Real>(a, b)(g_rng); }
Vec3 uniform_in(const Vec3& lo, const Vec3& hi) {
  return Vec3(uniform(lo[0], hi[0]), uniform(lo[1], hi[1]), uniform(lo[2], hi[2]));
}

// The nearest centre (or periodic image) of `set` within `reach` of x, by brute force.
bool brute_nearest(const gs::SphereSet& set, const gs::Domain& domain, const Vec3& x, Real reach,
                   Real& d2) {
  d2 = reach * reach;
  bool found = false;
  for (const Vec3& c : set.x)
    for (int sx = -1; sx <= 1; ++sx) {
      if (sx != 0 && !domain.periodic[0]) continue;
      Vec3 p = c;
      p[0] += sx * (domain.hi[0] - domain.lo[0]);
      const Real d = (p - x).squaredNorm();
      if (d < d2) {
        d2 = d;
        found = true;
      }
    }
  return found;
}

void nearest_matches_brute_force() {
  const gs::Domain domain(Vec3(0, 0, 0), Vec3(1, 1, 1), {true, false, false});
  for (int round = 0; round < 12; ++round) {
    gs::SphereSet set;
    const int n = round % 3 == 0 ? 5 : 400;  // sparse and dense
    for (int k = 0; k < n; ++k) {
      set.x.push_back(uniform_in(domain.lo, domain.hi));
      set.r.push_back(0.01);
    }
    const Vec3 lo = uniform_in(Vec3(0, 0, 0), Vec3(0.6, 0.6, 0.6));
    const Vec3 hi = lo + uniform_in(Vec3(0.05, 0.05, 0.05), Vec3(0.4, 0.4, 0.4));
    const Real reach = uniform(0.02, 0.3);
    const Real cell = reach * uniform(0.1, 1.5);
    const gs::CentreGrid grid(lo, hi, reach, cell, set, domain);
    for (int q = 0; q < 300; ++q) {
      const Vec3 x = uniform_in(lo, hi);
      const Real r = q % 2 ? reach : uniform(0, reach);  // any reach up to the grid's
      Real d2 = 0;
      const bool want = brute_nearest(set, domain, x, r, d2);
      Vec3 c;
      const bool got = grid.nearest(x, r, c);
      EXPECT(got == want, "found a centre within reach iff brute force does (round " +
                              std::to_string(round) + ")");
      if (got && want)
        EXPECT(std::abs((c - x).squaredNorm() - d2) <= 1e-15,
               "the nearest centre's distance equals brute force's");
    }
  }
}

}  // namespace

int main() {
  nearest_matches_brute_force();
  std::printf("test_centre_grid: %d checks, %d failed\n", test_support::g_checks,
              test_support::g_failures);
  return test_support::g_failures == 0 ? 0 : 1;
}
