// Shared helpers of the C++ microbenchmarks: wall-clock timing (median of repetitions),
// seeded lattice packings, ParticleStore set-up, the static packing of the force-loop figures,
// the interaction of the per-law figures and command-line scaling of N.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <random>
#include <string>
#include <vector>

#include "contact/interaction.hpp"
#include "core/types.hpp"
#include "neighbor/cell_grid.hpp"
#include "neighbor/neighbor_list.hpp"
#include "state/particle_store.hpp"

namespace bench {

using grainscale::Index;
using grainscale::Real;
using grainscale::Vec3;

inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// CPU time of the calling thread in ns (unaffected by time-sharing with other processes).
inline double thread_cpu_ns() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e9 * static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec);
}

// Median wall-clock (steady_clock) and thread-CPU time of a timed section, in ns.
struct Timing {
  double wall_ns;
  double cpu_ns;
  double min_wall_ns;  // fastest repetition (least disturbed by other processes)
};

// Runs setup() untimed, then body() timed, `reps` times; returns the medians of body().
// One untimed warm-up round runs first (page faults, caches, branch predictors).
template <class Setup, class Body>
Timing median_ns(int reps, Setup&& setup, Body&& body) {
  using Clock = std::chrono::steady_clock;
  setup();
  body();
  std::vector<double> wall, cpu;
  wall.reserve(reps);
  cpu.reserve(reps);
  for (int r = 0; r < reps; ++r) {
    setup();
    const double c0 = thread_cpu_ns();
    const auto t0 = Clock::now();
    body();
    const auto t1 = Clock::now();
    const double c1 = thread_cpu_ns();
    wall.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count());
    cpu.push_back(c1 - c0);
  }
  return {median(wall), median(cpu), *std::min_element(wall.begin(), wall.end())};
}

// Scale factor for N from argv[1] (default 1); exits with a usage message on a bad value.
inline double scale_from_args(int argc, char** argv) {
  if (argc < 2) return 1.0;
  char* end = nullptr;
  const double s = std::strtod(argv[1], &end);
  if (argc > 2 || end == argv[1] || *end != '\0' || !(s > 0) || !std::isfinite(s)) {
    std::fprintf(stderr, "usage: %s [scale]  (positive factor applied to every N, default 1)\n",
                 argv[0]);
    std::exit(2);
  }
  return s;
}

inline Index scaled(Index n, double scale) {
  return std::max<Index>(8, static_cast<Index>(std::llround(n * scale)));
}

// The first n sites of a simple-cubic lattice of n_side^3 >= n sites (x fastest), site spacing
// `spacing` along x and y and `spacing_z` along z, centred in the first octant at
// (spacing/2, spacing/2, spacing_z/2), each coordinate jittered by a seeded uniform offset in
// [-jitter, jitter].
inline std::vector<Vec3> lattice(Index n, Real spacing, Real spacing_z, Real jitter,
                                 std::uint64_t seed) {
  Index side = 1;
  while (static_cast<std::int64_t>(side) * side * side < n) ++side;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<Real> u(-jitter, jitter);
  std::vector<Vec3> x(n);
  for (Index k = 0; k < n; ++k) {
    const Index i = k % side, j = (k / side) % side, l = k / (side * side);
    x[k] = Vec3((i + 0.5) * spacing, (j + 0.5) * spacing, (l + 0.5) * spacing_z);
    if (jitter > 0)
      for (int a = 0; a < 3; ++a) x[k][a] += u(rng);
  }
  return x;
}

// Adds owned particles (ids 0..n-1, material 0, density rho) with optional velocities.
inline void fill_store(grainscale::ParticleStore& ps, const std::vector<Vec3>& x,
                       const std::vector<Real>& radius, Real rho,
                       const std::vector<Vec3>* velocity = nullptr,
                       const std::vector<Vec3>* angular_velocity = nullptr) {
  for (std::size_t k = 0; k < x.size(); ++k) {
    const Real r = radius[k];
    const Real m = rho * (4.0 / 3.0) * M_PI * r * r * r;
    ps.add_owned(
        static_cast<grainscale::GlobalId>(k), x[k], velocity ? (*velocity)[k] : Vec3::Zero(),
        angular_velocity ? (*angular_velocity)[k] : Vec3::Zero(), r, m, 0.4 * m * r * r, 0);
  }
}

// Reorders the owned particles into cell order, as Level::rebuild does before building lists
// (the force loop then walks memory mostly sequentially).
inline void spatial_sort(grainscale::ParticleStore& ps, Real cutoff) {
  grainscale::CellGrid grid;
  grid.build(ps.position.data(), ps.n_owned(), cutoff, 2 * ps.n_owned() + 64);
  const std::vector<Index> order(grid.particles.begin(), grid.particles.end());
  ps.select_owned(order);
}

inline Real max_radius(const grainscale::ParticleStore& ps) {
  Real r = 0;
  for (Index i = 0; i < ps.n_owned(); ++i) r = std::max(r, ps.radius[i]);
  return r;
}

// A static packing of d = 2 mm glass-like spheres (rho = 2500 kg/m^3) and its half list, whose
// history is sized for `history_stride` values per entry: a simple-cubic lattice of spacing
// `spacing` d with seeded uniform jitter of +-`jitter` d per coordinate, seeded random
// velocities (+-1 mm/s) and spins (+-1 rad/s), list built with a skin of 0.1 d, in cell order
// as in a Level. Defaults: the packing of bench_pair_loop (spacing 0.995 d, jitter 0.01 d).
struct Packing {
  grainscale::ParticleStore ps;
  grainscale::ContactList list;
};

constexpr Real kPackingDiameter = 2e-3;
constexpr Real kPackingDensity = 2500;

inline void make_packing(Index n, int history_stride, Packing& p, Real spacing = 0.995,
                         Real jitter = 0.01) {
  const Real d = kPackingDiameter, r = 0.5 * d, skin = 0.1 * d;
  std::vector<Vec3> x = lattice(n, spacing * d, spacing * d, jitter * d, 7);
  std::vector<Vec3> v(n), w(n);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<Real> u(-1, 1);
  for (Index i = 0; i < n; ++i) {
    v[i] = 1e-3 * Vec3(u(rng), u(rng), u(rng));
    w[i] = Vec3(u(rng), u(rng), u(rng));
  }
  fill_store(p.ps, x, std::vector<Real>(n, r), kPackingDensity, &v, &w);
  spatial_sort(p.ps, d + skin);
  grainscale::CellGrid grid;
  grid.build(p.ps.position.data(), p.ps.n_local(), d + skin, 2 * static_cast<std::size_t>(n) + 64);
  p.list.history_stride = history_stride;
  grainscale::build_pair_list(p.ps, grid, d + skin, skin, p.list);
}

// The interaction of the per-law figures; each normal model reads its own fields: e = 0.5,
// mu = 0.5, mu_r = 0.1, eta_r = 0.3; linear k_n derived from v_c = 1 m/s; EEPA n = 1 (or the
// environment's BENCH_EEPA_EXPONENT, e.g. 1.5), derived k1, k2/k1 = 3, k_adh = 50 N/m,
// f0 = -1e-4 N.
inline grainscale::Interaction law_interaction() {
  grainscale::Interaction in;
  in.restitution = 0.5;
  in.friction = 0.5;
  in.rolling_friction = 0.1;
  in.rolling_damping = 0.3;
  in.normal_stiffness = 0;  // linear: derived from E*, R*, m* and v_c
  in.characteristic_velocity = 1;
  in.eepa_exponent = 1;
  in.loading_stiffness = 0;  // EEPA: k1 = 2 E* R*
  in.unloading_ratio = 3;
  in.adhesive_stiffness = 50;  // N/m
  in.pull_off_force = -1e-4;   // N
  in.adhesion_exponent = 1;
  if (const char* n = std::getenv("BENCH_EEPA_EXPONENT")) in.eepa_exponent = std::atof(n);
  return in;
}

// One result line: "name: value unit (N=..., reps=..., cpu=..., min=...[, extra])". `value` is
// the median wall-clock figure; `cpu` the same from the thread's CPU time (shows how much of the
// wall time other processes on a busy machine took) and `min` from the fastest repetition.
inline void report(const std::string& name, const Timing& t, double divisor, const char* unit,
                   Index n, int reps, const std::string& extra = "") {
  std::printf("%s: %.4g %s (N=%d, reps=%d, cpu=%.4g, min=%.4g%s%s)\n", name.c_str(),
              t.wall_ns / divisor, unit, n, reps, t.cpu_ns / divisor, t.min_wall_ns / divisor,
              extra.empty() ? "" : ", ", extra.c_str());
  std::fflush(stdout);
}

}  // namespace bench
