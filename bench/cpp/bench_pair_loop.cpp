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
// 3. Per-law figure: accumulate_pair_forces<Law, true, false> for every alternative of
//    ContactLaw (iterated at compile time, named by Law::name()) on the same packing as 1., each
//    law with its own history developed by untimed warm-up calls (10 calls at dt = 2e-4 s: in a
//    static packing the same tangential and rolling spring increments as 200 steps of 1e-5 s).
//    One Interaction for all (each normal model reads its own fields): e = 0.5, mu = 0.5,
//    mu_r = 0.1, eta_r = 0.3; Hertz on E = 1e7 Pa; linear with k_n derived from E*, R*, m* and
//    v_c = 1 m/s (normal_stiffness = 0, the default; about 1.1e3 N/m against the Hertz tangent
//    stiffness of about 5e2 N/m at the mean overlap); EEPA with n = 1, derived k1 = 2 E* R*,
//    k2/k1 = 3, k_adh = 50 N/m, f0 = -1e-4 N (BENCH_EEPA_EXPONENT=1.5 in the environment:
//    n = 1.5 and k1 = 4/3 E* sqrt(R*); the state counts below assume n = 1). A static packing
//    would leave every EEPA contact on its loading branch, so the EEPA d_max history is seeded
//    (seeded RNG, the same for every EEPA law): half of the contacts d_max = d (loading), half
//    d_max = d (1 + 0.6 u), u uniform in [0, 1) (unloading, or adhesive where
//    d / d_max < 2 k1 / (3 k1 + k_adh)). The laws are timed interleaved (round-robin, start
//    rotated each round; one untimed round first), each call after restoring its developed
//    history; median per law. Figure: ns per touching contact and its ratio to hertz+none
//    (Hertz–Mindlin), checked against the target that every law with EEPA or rolling
//    resistance (eepa+*, *+cdt, *+epsd, *+epsd2) costs at most 1.3 x hertz+none (issue 27).
// 4. End-to-end Level::run(1000) of the 'settle' case (bench/python/settle_case.py: d = 2 mm on
//    a 2.2 mm lattice, square cross-section of ceil((N/2)^(1/3)) sites, jitter +-0.05 mm in x
//    and y, velocities +-0.05 m/s, six walls of the particle material, dt = 1e-5 s, skin
//    0.2 mm, gravity), timed from a fresh Level (first list build included): ns per
//    particle-step.
//
// Each line reports the median wall-clock figure, plus the same in thread CPU time (cpu=) and
// for the fastest repetition (min=): on a shared machine the spread between runs is large.
//
// Usage: bench_pair_loop [scale]   (N = 200k for the force loops, 50k for the Level, times scale)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "bench_common.hpp"
#include "contact/contact_law.hpp"
#include "contact/contact_model.hpp"
#include "contact/interaction.hpp"
#include "contact/pair_loop.hpp"
#include "geometry/wall.hpp"
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
  const Real dt = 1e-5;
  bench::Packing packing;
  bench::make_packing(n, HertzMindlin::kHistorySize, packing);
  grainscale::ParticleStore& ps = packing.ps;
  grainscale::ContactList& list = packing.list;

  grainscale::MaterialTable materials;
  materials.add(kGlass);
  grainscale::ContactSettings settings;
  settings.history = history;
  HertzMindlin law(settings);
  law.prepare(materials, interactions(materials));

  grainscale::ContactStats stats;
  for (int s = 0; s < 200; ++s) {
    zero_forces(ps);
    grainscale::accumulate_pair_forces<HertzMindlin, true, false>(law, ps, list, dt, stats);
  }
  const auto developed = list.history;

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

// 3. Per-law figure (see the top of the file).

constexpr int kWarmupCalls = 10;
constexpr Real kWarmupDtFactor = 20;  // warm-up dt / timed dt
constexpr double kTargetRatio = 1.3;  // EEPA and rolling laws: at most 1.3 x hertz+none

// Overlap of every list entry (<= 0: not touching).
std::vector<Real> entry_overlaps(const bench::Packing& p) {
  const grainscale::ParticleStore& ps = p.ps;
  const grainscale::ContactList& list = p.list;
  std::vector<Real> overlap(list.size(), 0);
  for (Index i = 0; i < ps.n_owned(); ++i)
    for (Index k = list.first[i]; k < list.first[i + 1]; ++k) {
      const Index j = list.partner[k];
      overlap[k] = ps.radius[i] + ps.radius[j] - (ps.position[i] - ps.position[j]).norm();
    }
  return overlap;
}

// Seeded EEPA d_max per entry: d (loading) for half of the touching entries, d (1 + 0.6 u) else.
std::vector<Real> seeded_d_max(const std::vector<Real>& overlap) {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<Real> u(0, 1);
  std::vector<Real> d_max(overlap.size(), 0);
  for (std::size_t k = 0; k < overlap.size(); ++k) {
    const Real a = u(rng), b = u(rng);
    if (overlap[k] > 0) d_max[k] = a < 0.5 ? overlap[k] : overlap[k] * (1 + 0.6 * b);
  }
  return d_max;
}

// One law of the figure, type-erased so that the laws can be timed round-robin.
class LawCase {
 public:
  virtual ~LawCase() = default;
  virtual std::string name() const = 0;
  // Restores the developed history and touching flags and zeroes the forces (untimed).
  virtual void setup() = 0;
  // One accumulate_pair_forces<Law, true, false> call (timed).
  virtual void run() = 0;

  std::int64_t contacts = 0;
  std::int64_t sliding = 0;  // compressive contacts at the Coulomb limit
  std::int64_t tensile = 0;  // F_n <= 0 (EEPA adhesion, damping)
  bool finite = true;
  std::vector<double> wall_ns, cpu_ns;
};

template <class Law>
class LawCaseFor final : public LawCase {
 public:
  LawCaseFor(bench::Packing& p, const grainscale::MaterialTable& materials,
             const std::vector<Real>& d_max, Real dt)
      : p_(p), law_(grainscale::ContactSettings{}), dt_(dt) {
    constexpr int S = Law::kHistorySize;
    const std::size_t stride = materials.n_materials() + 1;
    law_.prepare(materials,
                 std::vector<grainscale::Interaction>(stride * stride, bench::law_interaction()));
    grainscale::ContactList& list = p.list;
    list.history_stride = S;
    list.history.assign(list.size() * S, 0);
    list.touching.assign(list.size(), 0);
    if constexpr (std::is_same_v<typename Law::NormalModel, grainscale::EEPANormal>)
      for (std::size_t k = 0; k < list.size(); ++k) list.history[k * S] = d_max[k];
    grainscale::ContactStats stats;
    for (int s = 0; s < kWarmupCalls; ++s) {
      zero_forces(p.ps);
      grainscale::accumulate_pair_forces<Law, true, false>(law_, p.ps, list, kWarmupDtFactor * dt,
                                                           stats);
    }
    history_ = list.history;
    touching_ = list.touching;

    // Contact census on the developed state (kUpdate = false leaves the springs alone).
    stats.record = true;
    zero_forces(p.ps);
    grainscale::accumulate_pair_forces<Law, false, true>(law_, p.ps, list, dt, stats);
    contacts = stats.contacts;
    const Real mu = law_.pair(0, 0).friction;
    for (const grainscale::ContactRecord& c : stats.records) {
      const Real fn = c.force.dot(c.normal);
      const Real ft = (c.force - fn * c.normal).norm();
      if (fn > 0 && ft >= mu * fn * (1 - 1e-9)) ++sliding;
      if (fn <= 0) ++tensile;
      if (!c.force.allFinite()) finite = false;
    }
  }

  std::string name() const override { return Law::name(); }
  void setup() override {
    p_.list.history_stride = Law::kHistorySize;
    p_.list.history = history_;
    p_.list.touching = touching_;
    zero_forces(p_.ps);
  }
  void run() override {
    grainscale::accumulate_pair_forces<Law, true, false>(law_, p_.ps, p_.list, dt_, stats_);
  }

 private:
  bench::Packing& p_;
  Law law_;
  Real dt_;
  grainscale::PageVector<Real> history_;
  grainscale::PageVector<std::uint8_t> touching_;
  grainscale::ContactStats stats_;
};

// One LawCase per alternative of ContactLaw, in registry order.
template <std::size_t... I>
std::vector<std::unique_ptr<LawCase>> make_law_cases(std::index_sequence<I...>, bench::Packing& p,
                                                     const grainscale::MaterialTable& materials,
                                                     const std::vector<Real>& d_max, Real dt) {
  std::vector<std::unique_ptr<LawCase>> cases;
  (cases.push_back(
       std::make_unique<LawCaseFor<std::variant_alternative_t<I, grainscale::ContactLaw>>>(
           p, materials, d_max, dt)),
   ...);
  return cases;
}

// The laws the target applies to: eepa+*, *+epsd, *+epsd2.
bool target_law(const std::string& name) {
  const auto ends_with = [&](const std::string& s) {
    return name.size() >= s.size() && name.compare(name.size() - s.size(), s.size(), s) == 0;
  };
  return name.rfind("eepa+", 0) == 0 || ends_with("+cdt") || ends_with("+epsd") ||
         ends_with("+epsd2");
}

void bench_laws(Index n, int rounds) {
  const auto start = std::chrono::steady_clock::now();
  const Real dt = 1e-5;
  bench::Packing packing;
  bench::make_packing(n, 0, packing);
  grainscale::MaterialTable materials;
  materials.add(kGlass);
  const std::vector<Real> overlap = entry_overlaps(packing);
  const std::vector<Real> d_max = seeded_d_max(overlap);
  std::vector<std::unique_ptr<LawCase>> cases =
      make_law_cases(std::make_index_sequence<std::variant_size_v<grainscale::ContactLaw>>{},
                     packing, materials, d_max, dt);

  // State of the seeded EEPA contacts: at d_max (virgin loading), or below it on the unloading
  // line or the adhesive branch (n = 1; the formulas of EEPANormal::evaluate). At d = d_max
  // the loading and unloading forces agree to rounding, so the law may take either branch.
  const grainscale::Interaction in = bench::law_interaction();
  const Real r = 0.5 * kDiameter;
  const Real k1 = 2 * materials.pair_moduli(0, 0).effective_youngs * (r * r / (r + r));
  const Real k2 = in.unloading_ratio * k1;
  std::int64_t touching = 0, loading = 0, adhesive = 0;
  for (std::size_t k = 0; k < overlap.size(); ++k) {
    const Real d = overlap[k];
    if (!(d > 0)) continue;
    ++touching;
    if (d >= d_max[k])
      ++loading;
    else if (!(k2 * (d - (1 - k1 / k2) * d_max[k]) > -in.adhesive_stiffness * d))
      ++adhesive;
  }

  // Timed round-robin: one untimed round, then `rounds` rounds with the start rotated.
  for (const auto& c : cases) {
    c->setup();
    c->run();
  }
  const std::size_t n_laws = cases.size();
  for (int round = 0; round < rounds; ++round)
    for (std::size_t k = 0; k < n_laws; ++k) {
      LawCase& c = *cases[(k + round) % n_laws];
      c.setup();
      const double c0 = bench::thread_cpu_ns();
      const auto t0 = std::chrono::steady_clock::now();
      c.run();
      const auto t1 = std::chrono::steady_clock::now();
      const double c1 = bench::thread_cpu_ns();
      c.wall_ns.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count());
      c.cpu_ns.push_back(c1 - c0);
    }

  const LawCase* ref = nullptr;
  for (const auto& c : cases)
    if (c->name() == "hertz+none") ref = c.get();
  if (!ref) {
    std::printf("pair_loop_laws: error: no hertz+none law in ContactLaw\n");
    return;
  }
  const double entries = static_cast<double>(packing.list.size());
  std::printf(
      "pair_loop_laws: N=%d, rounds=%d, contacts/particle=%.2f, list entries/particle=%.2f, "
      "touching=%.0f%%, EEPA n=%g, seeded EEPA state (n = 1): at d_max=%.0f%%, "
      "unloading=%.0f%%, adhesive=%.0f%%\n",
      n, rounds, static_cast<double>(touching) / n, entries / n, 100 * touching / entries,
      in.eepa_exponent, 100.0 * loading / touching,
      100.0 * (touching - loading - adhesive) / touching, 100.0 * adhesive / touching);
  const double ref_ns = bench::median(ref->wall_ns) / static_cast<double>(ref->contacts);
  const double ref_cpu = bench::median(ref->cpu_ns) / static_cast<double>(ref->contacts);
  std::string missed;
  int n_target = 0, n_missed = 0;
  for (const auto& c : cases) {
    const std::string name = c->name();
    const double per = 1.0 / static_cast<double>(c->contacts);
    const double ns = bench::median(c->wall_ns) * per, ratio = ns / ref_ns;
    const double cpu = bench::median(c->cpu_ns) * per;
    const bool meets = ratio <= kTargetRatio;
    if (target_law(name)) {
      ++n_target;
      if (!meets) {
        ++n_missed;
        missed += (missed.empty() ? "" : ", ") + name;
      }
    }
    std::printf(
        "pair_loop[%s]: %.4g ns/contact (ratio to hertz+none: %.2f) <= %.1fx: %s%s (cpu=%.4g, "
        "cpu ratio=%.2f, min=%.4g, sliding=%.0f%%, tensile=%.0f%%)\n",
        name.c_str(), ns, ratio, kTargetRatio, meets ? "yes" : "NO",
        target_law(name) ? " [target law]" : "", cpu, cpu / ref_cpu,
        *std::min_element(c->wall_ns.begin(), c->wall_ns.end()) * per, 100.0 * c->sliding * per,
        100.0 * c->tensile * per);
    if (!c->finite) std::printf("warning: non-finite forces for %s\n", name.c_str());
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (n_missed == 0)
    std::printf(
        "pair_loop_laws: target (eepa+*, *+cdt, *+epsd, *+epsd2 <= %.1f x hertz+none) met by "
        "all "
        "%d target laws (%.0f s incl. set-up)\n",
        kTargetRatio, n_target, seconds);
  else
    std::printf(
        "pair_loop_laws: target (eepa+*, *+cdt, *+epsd, *+epsd2 <= %.1f x hertz+none) NOT "
        "met "
        "by %d of %d target laws: %s (%.0f s incl. set-up)\n",
        kTargetRatio, n_missed, n_target, missed.c_str(), seconds);
  std::fflush(stdout);
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
        grainscale::Wall wall;  // shape Plane
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
  bench_laws(n_loop, 15);
  bench_settle(bench::scaled(50000, scale), 1000, 3);
  return 0;
}
