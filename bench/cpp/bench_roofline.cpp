// Roofline of the particle-particle contact loop (accumulate_pair_forces) on one core.
//
// 1. The machine, measured here: memory bandwidth by a STREAM triad a[i] = b[i] + s c[i] over
//    three arrays of max(4 x LLC, 64 MiB) each (LLC: the largest cache in sysfs, 32 MiB if
//    unknown), best and median of 9 passes, counted as STREAM does (24 B per element; with
//    write-allocate the memory moves 32 B: the figure is printed too). Peak-ish flop rate: 12
//    independent multiply-add chains (x = x m + c, 2 flops, no FMA: the core is built with
//    -ffp-contract=off) in 8-wide vectors (GCC vector extension, split by the compiler into
//    what the target has: 1 AVX-512, 2 AVX or 4 SSE registers) and the same in scalar code
//    (vectorisation switched off for that function): the vector rate is the roof, the scalar
//    rate the ceiling of a loop that takes one contact at a time (the loop evaluates the law on
//    packs of kPackLanes contacts, core/simd_pack.hpp: printed with the machine line).
// 2. The packing: d = 2 mm glass-like spheres (E = 1e7 Pa, nu = 0.3, rho = 2500 kg/m^3) on a
//    simple-cubic lattice of spacing 0.99 d with seeded jitter of +-0.004 d per coordinate:
//    every lattice neighbour overlaps (by 1 % of d, +-0.8 %), about 3 contacts per particle in
//    the half list (coordination 6, a dense bed has 4-6), half list with skin 0.1 d in cell
//    order as in a Level (bench::make_packing). Seeded velocities (+-1 mm/s) and spins
//    (+-1 rad/s); each law's history developed by 10 untimed calls at dt = 2e-4 s and
//    restored before every timed call (dt = 1e-5 s). Settings as the LIGGGHTS-matched
//    benchmarks: total tangential history, projected springs, tangential damping, no force
//    limit; the interaction of bench::law_interaction (EEPA contacts all on their loading
//    branch here: d_max is not seeded).
// 3. Timing: accumulate_pair_forces<Law, kUpdate = true, kStats = false>, median of 15 calls,
//    "cold" (caches flushed by writing 2 x LLC before each call: every array comes from
//    memory, the roofline's assumption) and "warm" (no flush: what fits stays cached).
//    Figures: ns per touching contact and per particle (= per particle-step of this loop).
//
// Bytes per call (the compulsory traffic: every array element moved once between memory and
// core, j's data reused from cache thanks to the cell order; SoA layout of ParticleStore and
// ContactList, double = 8 B, Index and material = 4 B):
//   per particle i: reads  position, velocity, angular_velocity  3 x 24 B
//                          radius, inv_mass                      2 x 8 B
//                          material, first[i + 1]                2 x 4 B
//                   read + write  force, torque                  2 x 48 B
//                   (rolling laws) inv_rolling_inertia           8 B
//                   = 192 B (200 B with rolling)
//   per list entry: partner 4 B, touching flag 1 B read                       = 5 B
//   per touching contact: touching flag written 1 B, history S values read and
//                   written 16 S B (S = Law::kHistorySize: 3 for Hertz-Mindlin)  = 1 + 16 S B
// Without any reuse of j's data (the upper bound, printed too) a touching contact moves
// partner 4 + x, v, w 72 + r, inv_mass 16 + material 4 + f, t read + write 96 + flag 2 +
// history 16 S B (+ 8 rolling), a non-touching entry partner 4 + x 24 + r 8 + flag 1 B.
//
// Flops of Hertz-Mindlin (hertz+none, total history, projected spring, tangential damping),
// counted from pair_loop.hpp and contact_model.hpp / normal_models.hpp /
// tangential_models.hpp, sticking path; a division and a square root count 1 flop each (they
// cost 4-20 multiplications of throughput: 2 divisions and 3 roots per contact):
//   geometry: d = x_i - x_j 3, r_i + r_j 1, |d|^2 5, rsum^2 1, sqrt 1, overlap 1,
//     n = d (1 / dist) 4, contact arms a_i, a_j 3, a_i w_i + a_j w_j 9, cross with n 9,
//     v_rel 6, R* and m* from one reciprocal (pair_means) 6                       = 49
//   law: spring projected onto the tangent plane (dot 5, subtract 6) 11, Hertz sqrt(R* d)
//     and k_n, F_spring, S_n, k_t 9, v_n 5, F_n with damping 5, v_t 6, gamma_t 1,
//     mu F_n 1, spring += v_t dt 6, F_t = -k_t xi - gamma_t v_t 9, |F_t|^2 and the
//     Coulomb test 6, F = F_n n + F_t 6                                           = 65
//   accumulation: n x F 9, f_i 3, t_i 6, f_j 3, t_j 6                            = 27
//   = 141 per touching contact (a sliding one adds 16), 10 per non-touching entry
//   (d, rsum, |d|^2, rsum^2), 6 per particle (f_i, t_i stored). The other laws are
//   not counted: their line gives the memory roof only.
//
// Roofline limit per particle-step of the loop: max(bytes / bandwidth, flops / vector peak);
// the fraction printed is limit / measured (1 = at the roof). The best triad bandwidth is used
// (the most favourable to the machine, so the fraction is not flattered).
//
// Usage: bench_roofline [scale]   (N = 200k times scale; the triad and the flop rate do not
//                                  depend on it)
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "bench_common.hpp"
#include "contact/contact_law.hpp"
#include "contact/contact_model.hpp"
#include "contact/pair_loop.hpp"
#include "state/material_table.hpp"

namespace {

using bench::Index;
using bench::Real;
using Clock = std::chrono::steady_clock;

constexpr double kMiB = 1024.0 * 1024.0;

// Size of the last-level cache: the largest cache of CPU 0 in sysfs (K or M suffix), else
// sysconf's L3 (which some virtual machines report wrongly), else 32 MiB.
std::size_t llc_bytes() {
  static const std::size_t bytes = [] {
    std::size_t best = 0;
    for (int k = 0; k < 8; ++k) {
      const std::string path =
          "/sys/devices/system/cpu/cpu0/cache/index" + std::to_string(k) + "/size";
      std::FILE* f = std::fopen(path.c_str(), "r");
      if (!f) continue;
      unsigned long value = 0;
      char unit = 'K';
      if (std::fscanf(f, "%lu%c", &value, &unit) >= 1)
        best = std::max<std::size_t>(best, value << (unit == 'M' ? 20 : unit == 'K' ? 10 : 0));
      std::fclose(f);
    }
    const long v = sysconf(_SC_LEVEL3_CACHE_SIZE);
    if (best == 0 && v > 0) best = static_cast<std::size_t>(v);
    return best > 0 ? best : static_cast<std::size_t>(32 * kMiB);
  }();
  return bytes;
}

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Writes every cache line of a buffer of 2 x LLC: evicts the contact loop's data.
class CacheFlusher {
 public:
  CacheFlusher() : buffer_(2 * llc_bytes(), 1) {}
  void operator()() {
    for (std::size_t k = 0; k < buffer_.size(); k += 64) buffer_[k] = static_cast<char>(k);
  }

 private:
  std::vector<char> buffer_;
};

// 1. The machine.

struct Bandwidth {
  double best_gbs, median_gbs;  // STREAM convention: 24 B per element
  double array_mib;
};

Bandwidth stream_triad(int passes) {
  const std::size_t n = std::max<std::size_t>(4 * llc_bytes(), 64 * kMiB) / sizeof(double);
  std::vector<double> a(n, 0.0), b(n, 1.0), c(n, 2.0);  // pages touched before timing
  const double s = 3.0;
  std::vector<double> gbs;
  for (int p = 0; p < passes; ++p) {
    const auto t0 = Clock::now();
    for (std::size_t i = 0; i < n; ++i) a[i] = b[i] + s * c[i];
    const double t = seconds_since(t0);
    gbs.push_back(24.0 * static_cast<double>(n) / t * 1e-9);
  }
  if (a[n / 2] != 7.0) std::printf("warning: triad result %g, expected 7\n", a[n / 2]);
  return {*std::max_element(gbs.begin(), gbs.end()), bench::median(gbs), n * 8.0 / kMiB};
}

using Vec8 = double __attribute__((vector_size(64)));

// Flop rate of 12 independent chains x = x m + c in 8-wide vectors (GFLOP/s, best of 5).
double vector_mul_add_gflops(long iterations) {
  volatile double vm = 0.999999, vc = 1e-7;
  const double m = vm, c = vc;
  Vec8 x[12];
  for (int k = 0; k < 12; ++k)
    for (int l = 0; l < 8; ++l) x[k][l] = 1.0 + 1e-3 * (8 * k + l);
  double best = 0;
  for (int rep = 0; rep < 5; ++rep) {
    const auto t0 = Clock::now();
    for (long it = 0; it < iterations; ++it)
      for (int k = 0; k < 12; ++k) x[k] = x[k] * m + c;
    best = std::max(best, 2.0 * 12 * 8 * static_cast<double>(iterations) / seconds_since(t0));
  }
  double sum = 0;
  for (int k = 0; k < 12; ++k)
    for (int l = 0; l < 8; ++l) sum += x[k][l];
  if (!std::isfinite(sum)) std::printf("warning: non-finite flop kernel\n");
  return best * 1e-9;
}

// The same in scalar code (12 chains, no vectorisation).
#if defined(__GNUC__) && !defined(__clang__)
[[gnu::optimize("no-tree-vectorize")]]
#endif
double scalar_mul_add_gflops(long iterations) {
  volatile double vm = 0.999999, vc = 1e-7;
  const double m = vm, c = vc;
  double x[12];
  for (int k = 0; k < 12; ++k) x[k] = 1.0 + 1e-3 * k;
  double best = 0;
  for (int rep = 0; rep < 5; ++rep) {
    const auto t0 = Clock::now();
    for (long it = 0; it < iterations; ++it)
#pragma GCC unroll 12
      for (int k = 0; k < 12; ++k) x[k] = x[k] * m + c;
    best = std::max(best, 2.0 * 12 * static_cast<double>(iterations) / seconds_since(t0));
  }
  double sum = 0;
  for (double v : x) sum += v;
  if (!std::isfinite(sum)) std::printf("warning: non-finite flop kernel\n");
  return best * 1e-9;
}

// 2. and 3. The contact loop.

// Compulsory bytes per call, per particle (see the top of the file).
double compulsory_bytes_per_particle(int history, bool rolling, double entries_pp,
                                     double contacts_pp) {
  const double particle = 3 * 24 + 2 * 8 + 2 * 4 + 2 * 48 + (rolling ? 8 : 0);
  return particle + 5 * entries_pp + (1 + 16.0 * history) * contacts_pp;
}

// Bytes per call without reuse of j's data, per particle (see the top of the file).
double no_reuse_bytes_per_particle(int history, bool rolling, double entries_pp,
                                   double contacts_pp) {
  const double particle = 3 * 24 + 2 * 8 + 2 * 4 + 2 * 48 + (rolling ? 8 : 0);
  const double contact = 4 + 72 + 16 + 4 + 96 + 2 + 16.0 * history + (rolling ? 8 : 0);
  return particle + 37 * (entries_pp - contacts_pp) + contact * contacts_pp;
}

// Flops of hertz+none per call, per particle (sticking path; see the top of the file).
double hertz_mindlin_flops_per_particle(double entries_pp, double contacts_pp) {
  return 6 + 10 * (entries_pp - contacts_pp) + 141 * contacts_pp;
}

struct LawFigures {
  std::string name;
  int history = 0;
  bool rolling = false;
  double contacts = 0, sliding = 0;
  bench::Timing cold{}, warm{};
  bool finite = true;
};

void zero_forces(grainscale::ParticleStore& ps) {
  for (Index i = 0; i < ps.n_local(); ++i) {
    ps.force[i].setZero();
    ps.torque[i].setZero();
  }
}

template <class Law>
LawFigures time_law(bench::Packing& p, const grainscale::MaterialTable& materials,
                    CacheFlusher& flush, int reps) {
  constexpr int S = Law::kHistorySize;
  const Real dt = 1e-5;
  grainscale::ContactSettings settings;
  settings.limit_force = false;
  settings.tangential_damping = true;
  settings.history = grainscale::TangentialHistory::Total;
  settings.spring_rotation = grainscale::SpringRotation::Project;
  Law law(settings);
  const std::size_t stride = materials.n_materials() + 1;
  law.prepare(materials,
              std::vector<grainscale::Interaction>(stride * stride, bench::law_interaction()));
  grainscale::ContactList& list = p.list;
  list.history_stride = S;
  list.history.assign(list.size() * S, 0);
  list.touching.assign(list.size(), 0);
  grainscale::ContactStats stats;
  for (int s = 0; s < 10; ++s) {
    zero_forces(p.ps);
    grainscale::accumulate_pair_forces<Law, true, false>(law, p.ps, list, 20 * dt, stats);
  }
  const auto history = list.history;
  const auto touching = list.touching;

  LawFigures fig;
  fig.name = Law::name();
  fig.history = S;
  fig.rolling = Law::kRolling;
  stats.record = true;  // census of the developed state (kUpdate = false: springs unchanged)
  zero_forces(p.ps);
  grainscale::accumulate_pair_forces<Law, false, true>(law, p.ps, list, dt, stats);
  fig.contacts = static_cast<double>(stats.contacts);
  const Real mu = law.pair(0, 0).friction;
  for (const grainscale::ContactRecord& c : stats.records) {
    const Real fn = c.force.dot(c.normal);
    if (fn > 0 && (c.force - fn * c.normal).norm() >= mu * fn * (1 - 1e-9)) ++fig.sliding;
    if (!c.force.allFinite()) fig.finite = false;
  }
  stats.record = false;
  const auto restore = [&] {
    list.history = history;
    list.touching = touching;
    zero_forces(p.ps);
  };
  const auto call = [&] {
    grainscale::accumulate_pair_forces<Law, true, false>(law, p.ps, list, dt, stats);
  };
  fig.cold = bench::median_ns(
      reps,
      [&] {
        restore();
        flush();
      },
      call);
  fig.warm = bench::median_ns(reps, restore, call);
  return fig;
}

template <std::size_t... I>
std::vector<LawFigures> time_laws(std::index_sequence<I...>, bench::Packing& p,
                                  const grainscale::MaterialTable& materials, CacheFlusher& flush,
                                  int reps) {
  return {time_law<std::variant_alternative_t<I, grainscale::ContactLaw>>(p, materials, flush,
                                                                          reps)...};
}

}  // namespace

int main(int argc, char** argv) {
  const double scale = bench::scale_from_args(argc, argv);
  const Index n = bench::scaled(200000, scale);
  const auto start = Clock::now();

  // 1. The machine.
  const Bandwidth bw = stream_triad(9);
  const double vec_gflops = vector_mul_add_gflops(20'000'000);
  const double scalar_gflops = scalar_mul_add_gflops(20'000'000);
  std::printf(
      "machine: LLC %.0f MiB; STREAM triad (3 arrays of %.0f MiB, one core): best %.2f GB/s, "
      "median %.2f GB/s (24 B/element; with write-allocate %.2f GB/s moved)\n",
      llc_bytes() / kMiB, bw.array_mib, bw.best_gbs, bw.median_gbs, bw.best_gbs * 32 / 24);
  std::printf(
      "machine: mul+add (no FMA) peak-ish: %.2f GFLOP/s in 8-wide vectors, %.2f GFLOP/s "
      "scalar; the contact loop evaluates %d contacts per pack\n",
      vec_gflops, scalar_gflops, grainscale::kPackLanes);

  // 2. The packing.
  bench::Packing packing;
  bench::make_packing(n, 0, packing, 0.99, 0.004);
  grainscale::MaterialTable materials;
  materials.add(grainscale::MaterialProperties{bench::kPackingDensity, 1e7, 0.3});
  const double entries = static_cast<double>(packing.list.size());
  CacheFlusher flush;

  // 3. Every law.
  std::vector<LawFigures> laws =
      time_laws(std::make_index_sequence<std::variant_size_v<grainscale::ContactLaw>>{}, packing,
                materials, flush, 15);
  const double contacts = laws.front().contacts;
  const double entries_pp = entries / n, contacts_pp = contacts / n;
  std::printf(
      "packing: N=%d, list entries/particle=%.3f, contacts/particle=%.3f (coordination %.2f), "
      "touching=%.0f%%, working set of the loop %.1f MiB\n",
      n, entries_pp, contacts_pp, 2 * contacts_pp, 100 * contacts / entries,
      compulsory_bytes_per_particle(3, false, entries_pp, contacts_pp) * n / kMiB);

  for (const LawFigures& f : laws) {
    const double c_pp = f.contacts / n;
    const double bytes = compulsory_bytes_per_particle(f.history, f.rolling, entries_pp, c_pp);
    const double bytes_nr = no_reuse_bytes_per_particle(f.history, f.rolling, entries_pp, c_pp);
    const double t_mem = bytes / bw.best_gbs;  // ns per particle (GB/s = B/ns)
    const double cold_pp = f.cold.wall_ns / n, warm_pp = f.warm.wall_ns / n;
    std::printf(
        "roofline[%s]: cold %.2f ns/contact, %.2f ns/particle-step (cpu %.2f, min %.2f); warm "
        "%.2f ns/contact, %.2f ns/particle-step; bytes/particle %.0f (no reuse %.0f), "
        "memory roof %.2f ns/particle-step",
        f.name.c_str(), f.cold.wall_ns / f.contacts, cold_pp, f.cold.cpu_ns / n,
        f.cold.min_wall_ns / n, f.warm.wall_ns / f.contacts, warm_pp, bytes, bytes_nr, t_mem);
    if (f.name == "hertz+none") {
      const double flops = hertz_mindlin_flops_per_particle(entries_pp, c_pp);
      const double t_vec = flops / vec_gflops, t_scalar = flops / scalar_gflops;
      const double limit = std::max(t_mem, t_vec);
      std::printf(
          "; flops/particle %.0f (%.0f/contact), %.2f flop/B; flop roof %.2f ns (scalar "
          "ceiling %.2f ns); roofline limit %.2f ns/particle-step (%s-bound); fraction of the "
          "limit reached: cold %.2f, warm %.2f; of the scalar ceiling: cold %.2f",
          flops, flops / c_pp, flops / bytes, t_vec, t_scalar, limit,
          t_mem >= t_vec ? "memory" : "compute", limit / cold_pp, limit / warm_pp,
          std::max(t_mem, t_scalar) / cold_pp);
    } else {
      std::printf("; fraction of the memory roof reached: cold %.2f, warm %.2f", t_mem / cold_pp,
                  t_mem / warm_pp);
    }
    std::printf(" (sliding %.0f%%)\n", 100 * f.sliding / std::max(f.contacts, 1.0));
    if (!f.finite) std::printf("warning: non-finite forces for %s\n", f.name.c_str());
  }
  std::printf("roofline: done in %.0f s (incl. set-up)\n", seconds_since(start));
  return 0;
}
