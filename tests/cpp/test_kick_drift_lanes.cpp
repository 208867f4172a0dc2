// kick_drift and kick_drift_except (blocks of kPackLanes particles, integrate/
// kick_drift_lanes.hpp) checked bit for bit against the velocity-Verlet pass written out one
// particle at a time: every particle count around the block width, the opening step (one half
// kick) and later ones (two), skip masks with whole blocks clear and blocks partly skipped, 2-D,
// and NaN velocities in a block and in the remainder (the result is NaN). Prints every failed
// check and returns non-zero if any failed.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "core/simd_pack.hpp"
#include "expect.hpp"
#include "integrate/velocity_verlet.hpp"
#include "state/particle_store.hpp"

namespace gs = grainscale;
using gs::Index;
using gs::Real;
using gs::Vec3;

namespace {

std::mt19937_64 g_rng;
Real uniform(Real a, Real b) { return std::uniform_real_distribution<Real>(a, b)(g_rng); }
Vec3 random_vec(Real scale) {
  return Vec3(uniform(-scale, scale), uniform(-scale, scale), uniform(-scale, scale));
}

// Two calls with the same seed give equal stores (a copy of a store would share its buffers).
gs::ParticleStore random_store(Index n, unsigned seed) {
  g_rng.seed(seed);
  gs::ParticleStore ps;
  for (Index i = 0; i < n; ++i) {
    const Real r = uniform(1e-4, 2e-3), m = uniform(1e-6, 1e-2);
    ps.add_owned(i, random_vec(0.1), random_vec(1), random_vec(100), r, m, 0.4 * m * r * r, 0);
    ps.force[i] = random_vec(1e-2);
    ps.torque[i] = random_vec(1e-6);
  }
  return ps;
}

// The pass one particle at a time (velocity_verlet.hpp's definition), on particles without
// skip[i]; returns the largest |v|^2, NaN if any is NaN.
Real reference(gs::ParticleStore& ps, Real dt, const Vec3& g, bool closing, bool planar,
               const std::vector<std::uint8_t>* skip) {
  const Real half = 0.5 * dt;
  Real most = 0;
  bool nan = false;
  for (Index i = 0; i < ps.n_owned(); ++i) {
    if (skip && (*skip)[i]) continue;
    const Real hm = half * ps.inv_mass[i], hi = half * ps.inv_inertia[i];
    Vec3 v = ps.velocity[i], w = ps.angular_velocity[i];
    const Vec3 f = ps.force[i], t = ps.torque[i];
    for (int kick = closing ? 0 : 1; kick < 2; ++kick) {
      if (planar) {
        v[0] += hm * f[0];
        v[1] += hm * f[1];
        v[2] = 0;
        w[0] = 0;
        w[1] = 0;
        w[2] += hi * t[2];
      } else {
        v += hm * f;
        w += hi * t;
      }
    }
    ps.position[i] = ps.position[i] + dt * v;
    ps.velocity[i] = v;
    ps.angular_velocity[i] = w;
    ps.force[i] = ps.mass[i] * g;
    ps.torque[i].setZero();
    const Real v2 = (v[0] * v[0] + v[1] * v[1]) + v[2] * v[2];
    nan |= v2 != v2;
    if (v2 > most) most = v2;
  }
  return nan ? std::nan("") : most;
}

bool same_bits(const gs::SharedArray<Vec3>& a, const gs::SharedArray<Vec3>& b, Index n) {
  return n == 0 || std::memcmp(a.data(), b.data(), sizeof(Vec3) * static_cast<std::size_t>(n)) == 0;
}

void check_same(const gs::ParticleStore& got, const gs::ParticleStore& want, Real got_v2,
                Real want_v2, const std::string& what) {
  const Index n = want.n_owned();
  EXPECT(same_bits(got.position, want.position, n), what + ": positions");
  EXPECT(same_bits(got.velocity, want.velocity, n), what + ": velocities");
  EXPECT(same_bits(got.angular_velocity, want.angular_velocity, n), what + ": spins");
  EXPECT(same_bits(got.force, want.force, n), what + ": forces reset to m g");
  EXPECT(same_bits(got.torque, want.torque, n), what + ": torques reset to 0");
  EXPECT((got_v2 == want_v2) || (got_v2 != got_v2 && want_v2 != want_v2),
         what + ": largest |v|^2 " + std::to_string(got_v2) + " vs " + std::to_string(want_v2));
}

void blocks_match_one_at_a_time() {
  const Real dt = 1e-5;
  const Vec3 g(0.3, -0.2, -9.81);
  const int lanes = gs::kPackLanes;
  unsigned seed = 0;
  for (Index n : {0, 1, lanes - 1, lanes, lanes + 1, 3 * lanes - 1, 3 * lanes + 2, 257, 1003}) {
    if (n < 0) continue;
    const std::string size = "n = " + std::to_string(n);
    for (bool closing : {false, true}) {
      ++seed;
      gs::ParticleStore a = random_store(n, seed), b = random_store(n, seed);
      const Real got =
          closing ? gs::kick_drift<false, true>(a, dt, g) : gs::kick_drift<false, false>(a, dt, g);
      const Real want = reference(b, dt, g, closing, false, nullptr);
      check_same(a, b, got, want, size + (closing ? ", two half kicks" : ", one half kick"));
    }
    {  // 2-D keeps the one-at-a-time pass
      ++seed;
      gs::ParticleStore a = random_store(n, seed), b = random_store(n, seed);
      const Real got = gs::kick_drift<true, true>(a, dt, g);
      const Real want = reference(b, dt, g, true, true, nullptr);
      check_same(a, b, got, want, size + ", 2-D");
    }
    // Skip masks: none, every third particle, and a run of skipped particles (whole blocks
    // clear around it), as the ghost exchange defers the particles near a subdomain face.
    for (int pattern = 0; pattern < 3; ++pattern) {
      std::vector<std::uint8_t> skip(static_cast<std::size_t>(n), 0);
      for (Index i = 0; i < n; ++i)
        skip[i] = pattern == 1 ? i % 3 == 0 : pattern == 2 ? (i >= n / 3 && i < n / 2) : 0;
      ++seed;
      gs::ParticleStore a = random_store(n, seed), b = random_store(n, seed);
      const Real got = gs::kick_drift_except<false>(a, dt, g, skip);
      const Real want = reference(b, dt, g, true, false, &skip);
      check_same(a, b, got, want, size + ", skip pattern " + std::to_string(pattern));
    }
  }
}

void nan_velocity_gives_nan() {
  const Real dt = 1e-5;
  const Vec3 g(0, 0, -9.81);
  const Index n = 4 * gs::kPackLanes + 3;
  for (Index bad : {Index(0), Index(gs::kPackLanes + 1), n - 1}) {  // in blocks and the rest
    gs::ParticleStore a = random_store(n, 99);
    a.velocity[bad][1] = std::nan("");
    const Real got = gs::kick_drift<false, true>(a, dt, g);
    EXPECT(got != got, "a NaN velocity of particle " + std::to_string(bad) + " gives NaN");
  }
}

}  // namespace

int main() {
  blocks_match_one_at_a_time();
  nan_velocity_gives_nan();
  std::printf("test_kick_drift_lanes: %d checks, %d failed\n", test_support::g_checks,
              test_support::g_failures);
  return test_support::g_failures == 0 ? 0 : 1;
}
