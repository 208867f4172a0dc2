// Microbenchmark of the particle-particle force loop and of a whole Level.
//
// 1. and 2. accumulate_pair_forces<HertzMindlin, kUpdate = true, kStats = false> (HertzMindlin =
//    ContactModel<HertzNormal, HertzDamping, NoRolling>, the default law) on a static packing: d =
//    2 mm glass-like spheres (E = 1e7 Pa, nu = 0.3, rho = 2500 kg/m^3, e = 0.5, mu = 0.5) on a
//    simple-cubic lattice of spacing 0.995 d with seeded uniform jitter of
//    +-0.01 d per coordinate, so lattice neighbours overlap by 0.5 % of d on average and about
//    70 % of them touch; half list built with a skin of 0.1 d, in cell order as in a Level.
//    Seeded random velocities (+-1 mm/s) and spins (+-1 rad/s); the tangential springs are
//    developed by 200 untimed calls (dt = 1e-5 s) and restored before every timed call, so
//    each repetition sees the same mix of sticking and sliding contacts. Variants: tangential
//    history Total and Incremental. Figures: ns per touching contact and ns per list entry.
// 3. End-to-end Level::run(1000) of the 'settle' case (bench/python/settle_case.py: d = 2 mm on
//    a 2.2 mm lattice, square cross-section of ceil((N/2)^(1/3)) sites, jitter +-0.05 mm in x
//    and y, velocities +-0.05 m/s, six walls of the particle material, dt = 1e-5 s, skin
//    0.2 mm, gravity), timed from a fresh Level (first list build included): ns per
//    particle-step.
//
// Each line reports the median wall-clock figure, plus the same in thread CPU time (cpu=) and
// for the fastest repetition (min=): on a shared machine the spread between runs is large.
//
// Usage: bench_pair_loop [scale]   (N = 200k for the force loop, 50k for the Level, times scale)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "contact/contact_law.hpp"
#include "contact/contact_model.hpp"
#include "contact/interaction.hpp"
#include "contact/pair_loop.hpp"
#include "geometry/plane_wall.hpp"
#include "level/level.hpp"
#include "neighbor/cell_grid.hpp"
#include "neighbor/neighbor_list.hpp"
#include "state/material_table.hpp"
#include "state/particle_store.hpp"

namespace {

using bench::Index;
using bench::Real;
using bench::Vec3;

constexpr Real kDiameter = 2e-3;
constexpr Real kDensity = 2500;
const grainscale::MaterialProperties kGlass{kDensity, 1e7, 0.3};

// Hertz-Mindlin with LIGGGHTS-type damping, no rolling resistance (the default law).
using HertzMindlin = grainscale::ContactModel<grainscale::HertzNormal, grainscale::HertzDamping,
                                              grainscale::NoRolling>;

// e = 0.5, mu = 0.5 for every material pair, walls included.
std::vector<grainscale::Interaction> interactions(const grainscale::MaterialTable& materials) {
  grainscale::Interaction in;
  in.restitution = 0.5;
  in.friction = 0.5;
  const std::size_t stride = materials.n_materials() + 1;
  return std::vector<grainscale::Interaction>(stride * stride, in);
}

void zero_forces(grainscale::ParticleStore& ps) {
  for (Index i = 0; i < ps.n_local(); ++i) {
    ps.force[i].setZero();
    ps.torque[i].setZero();
  }
}

void bench_force_loop(Index n, grainscale::TangentialHistory history, const std::string& name,
                      int reps) {
  const Real d = kDiameter, r = 0.5 * d, skin = 0.1 * d, dt = 1e-5;
  std::vector<Vec3> x = bench::lattice(n, 0.995 * d, 0.995 * d, 0.01 * d, 7);
  std::vector<Vec3> v(n), w(n);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<Real> u(-1, 1);
  for (Index i = 0; i < n; ++i) {
    v[i] = 1e-3 * Vec3(u(rng), u(rng), u(rng));
    w[i] = Vec3(u(rng), u(rng), u(rng));
  }
  grainscale::ParticleStore ps;
  bench::fill_store(ps, x, std::vector<Real>(n, r), kDensity, &v, &w);
  bench::spatial_sort(ps, d + skin);

  grainscale::MaterialTable materials;
  materials.add(kGlass);
  grainscale::ContactSettings settings;
  settings.history = history;
  HertzMindlin law(settings);
  law.prepare(materials, interactions(materials));

  grainscale::CellGrid grid;
  grid.build(ps.position.data(), ps.n_local(), d + skin, 2 * static_cast<std::size_t>(n) + 64);
  grainscale::ContactList list;
  list.history_stride = HertzMindlin::kHistorySize;
  grainscale::build_pair_list(ps, grid, skin, list);

  grainscale::ContactStats stats;
  for (int s = 0; s < 200; ++s) {
    zero_forces(ps);
    grainscale::accumulate_pair_forces<HertzMindlin, true, false>(law, ps, list, dt, stats);
  }
  const std::vector<Real> developed = list.history;

  // Contact census on the developed state (kUpdate = false leaves the springs alone).
  stats.record = true;
  zero_forces(ps);
  grainscale::accumulate_pair_forces<HertzMindlin, false, true>(law, ps, list, dt, stats);
  const double contacts = static_cast<double>(stats.contacts);
  Index sliding = 0;
  const HertzMindlin::Pair& pair = law.pair(0, 0);
  for (const grainscale::ContactRecord& c : stats.records) {
    const Real fn = c.force.dot(c.normal);
    const Real ft = (c.force - fn * c.normal).norm();
    if (fn > 0 && ft >= pair.friction * fn * (1 - 1e-9)) ++sliding;
  }

  stats.record = false;
  const bench::Timing t = bench::median_ns(
      reps,
      [&] {
        list.history = developed;
        zero_forces(ps);
      },
      [&] {
        grainscale::accumulate_pair_forces<HertzMindlin, true, false>(law, ps, list, dt, stats);
      });
  Real checksum = 0;
  for (Index i = 0; i < n; ++i) checksum += ps.force[i].squaredNorm();
  if (!std::isfinite(checksum)) std::printf("warning: non-finite forces\n");

  const double entries = static_cast<double>(list.size());
  char extra[160];
  std::snprintf(extra, sizeof extra,
                "contacts/particle=%.2f, list entries/particle=%.2f, touching=%.0f%%, "
                "sliding=%.0f%%",
                contacts / n, entries / n, 100 * contacts / entries, 100 * sliding / contacts);
  bench::report(name, t, contacts, "ns/contact", n, reps, extra);
  bench::report(name + "_per_entry", t, entries, "ns/entry", n, reps, extra);
}

// The 'settle' case of bench/python/settle_case.py, with std::mt19937_64 instead of numpy.
void bench_settle(Index n, int steps, int reps) {
  const Real d = kDiameter, spacing = 2.2e-3, jitter = 0.05e-3, speed = 0.05;
  Index side = 1;
  while (2 * static_cast<std::int64_t>(side) * side * side < n) ++side;
  const Index layers = (n + side * side - 1) / (side * side);
  const Vec3 hi(side * spacing, side * spacing, layers * spacing + spacing);

  std::vector<Real> pos(3 * static_cast<std::size_t>(n)), vel(pos.size()), rad(n, 0.5 * d);
  std::vector<std::int32_t> mat(n, 0);
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<Real> uj(-jitter, jitter), uv(-speed, speed);
  for (Index k = 0; k < n; ++k) {
    const Index layer = k / (side * side), row = (k % (side * side)) / side, col = k % side;
    pos[3 * k] = (col + 0.5) * spacing + uj(rng);
    pos[3 * k + 1] = (row + 0.5) * spacing + uj(rng);
    pos[3 * k + 2] = (layer + 0.5) * spacing;
  }
  for (Real& value : vel) value = uv(rng);

  std::vector<double> seconds, cpu_seconds;
  std::int64_t rebuilds = 0, contacts = 0, lost = 0;
  for (int rep = 0; rep < reps; ++rep) {
    grainscale::Level level(grainscale::Domain(Vec3::Zero(), hi, {false, false, false}));
    const int m = level.add_material(kGlass);
    grainscale::ContactSettings settings;
    settings.limit_force = false;
    settings.tangential_damping = true;
    settings.history = grainscale::TangentialHistory::Total;
    level.set_contact_law(grainscale::make_contact_law("hertz", "none", settings));
    grainscale::Interaction interaction;
    interaction.restitution = 0.5;
    interaction.friction = 0.5;
    level.set_default_interaction(interaction);
    level.set_gravity(Vec3(0, 0, -9.81));
    level.set_time_step(1e-5, false);
    level.set_skin(0.2e-3);
    level.add_particles(n, pos.data(), vel.data(), nullptr, rad.data(), mat.data());
    const Vec3 corner[2] = {Vec3::Zero(), hi};
    for (int a = 0; a < 3; ++a)
      for (int side_hi = 0; side_hi < 2; ++side_hi) {
        grainscale::PlaneWall wall;
        wall.point = corner[side_hi];
        wall.normal = Vec3::Zero();
        wall.normal[a] = side_hi ? -1 : 1;
        wall.material = m;
        level.add_wall(wall);
      }
    const double c0 = bench::thread_cpu_ns();
    const auto t0 = std::chrono::steady_clock::now();
    level.run(steps);
    const auto t1 = std::chrono::steady_clock::now();
    cpu_seconds.push_back(1e-9 * (bench::thread_cpu_ns() - c0));
    seconds.push_back(std::chrono::duration<double>(t1 - t0).count());
    rebuilds = level.rebuilds();
    contacts = level.last_stats().contacts;
    lost = level.lost_particles();
  }
  char extra[160];
  std::snprintf(extra, sizeof extra,
                "steps=%d, rebuilds=%lld, contacts at end=%lld (incl. walls), lost=%lld", steps,
                static_cast<long long>(rebuilds), static_cast<long long>(contacts),
                static_cast<long long>(lost));
  const bench::Timing t{1e9 * bench::median(seconds), 1e9 * bench::median(cpu_seconds),
                        1e9 * *std::min_element(seconds.begin(), seconds.end())};
  bench::report("level_settle", t, static_cast<double>(n) * steps, "ns/particle-step", n, reps,
                extra);
}

}  // namespace

int main(int argc, char** argv) {
  const double scale = bench::scale_from_args(argc, argv);
  const Index n_loop = bench::scaled(200000, scale);
  bench_force_loop(n_loop, grainscale::TangentialHistory::Total, "pair_loop_hertz_mindlin_total",
                   21);
  bench_force_loop(n_loop, grainscale::TangentialHistory::Incremental,
                   "pair_loop_hertz_mindlin_incremental", 21);
  bench_settle(bench::scaled(50000, scale), 1000, 3);
  return 0;
}
