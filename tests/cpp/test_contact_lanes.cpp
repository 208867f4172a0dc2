// The contact laws on packs of contacts give the scalar law's bits (core/simd_pack.hpp), and the
// batched pair loop (contact/pair_loop.hpp) the forces, torques and histories of a loop that
// takes one contact at a time, in the same summation order: bit for bit, for every law and
// setting, with two materials (lanes of different pairs) and histories on every branch
// (sticking and sliding springs, EEPA loading and unloading, linear stiffness stored or not);
// with one sphere much larger than the rest (rows longer than a batch). The batched wall loop
// (contact/wall_loop.hpp) likewise gives the one-contact wall loop's bits, loads on the walls
// included.
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <variant>
#include <vector>

#include "contact/contact_law.hpp"
#include "contact/pair_loop.hpp"
#include "contact/wall_loop.hpp"
#include "expect.hpp"
#include "neighbor/cell_grid.hpp"
#include "neighbor/neighbor_list.hpp"
#include "state/material_table.hpp"
#include "state/particle_store.hpp"

namespace gs = grainscale;
using gs::Index;
using gs::Real;
using gs::Vec3;

namespace {

bool same_bits(Real a, Real b) { return std::memcmp(&a, &b, sizeof(Real)) == 0; }
bool same_bits(const Vec3& a, const Vec3& b) {
  return same_bits(a[0], b[0]) && same_bits(a[1], b[1]) && same_bits(a[2], b[2]);
}

// The two lists' histories, value for value, bit for bit.
bool same_histories(const gs::ContactList& a, const gs::ContactList& b) {
  if (a.history.size() != b.history.size()) return false;
  for (std::size_t k = 0; k < a.history.size(); ++k)
    if (!same_bits(a.history[k], b.history[k])) return false;
  return true;
}

// Two materials; the pair constants differ between all four combinations (and the walls).
void prepare(gs::ContactLaw& law) {
  gs::MaterialTable materials;
  materials.add({2500.0, 1e7, 0.3});
  materials.add({1200.0, 3e6, 0.25});
  const int stride = materials.n_materials() + 1;
  std::vector<gs::Interaction> in(stride * stride);
  for (int i = 0; i < stride; ++i)
    for (int j = 0; j < stride; ++j) {
      gs::Interaction& x = in[i * stride + j];
      const int k = i + j;  // symmetric
      x.restitution = 0.3 + 0.1 * k;
      x.friction = 0.3 + 0.05 * k;
      x.rolling_friction = 0.05 + 0.02 * k;
      x.rolling_damping = k == 1 ? 0.0 : 0.3;       // eta_r = 0 on the mixed pair
      x.normal_stiffness = k == 0 ? 0.0 : 2e3 * k;  // derived on (0, 0), given elsewhere
      x.tangential_stiffness = k == 2 ? 500.0 : 0.0;
      x.characteristic_velocity = 0.5 + k;
      x.eepa_exponent = k == 0 ? 1.0 : (k == 1 ? 1.5 : 1.3);  // every power path
      x.loading_stiffness = k == 2 ? 4e3 : 0.0;
      x.unloading_ratio = 3 + k;
      x.adhesive_stiffness = 500.0 * (1 + k);
      x.pull_off_force = -1e-4 * k;
      x.adhesion_exponent = k == 1 ? 1.0 : 1.5;
    }
  std::visit([&](auto& l) { l.prepare(materials, in); }, law);
}

struct Contact {
  gs::ContactInput input;
  int mi, mj;
  std::vector<Real> history;
};

// Random contacts near touch: a quarter with a spring beyond the Coulomb limit (sliding), a
// quarter with an empty history, EEPA d_max above or below the overlap.
std::vector<Contact> random_contacts(int count, int history_size, std::mt19937_64& rng) {
  std::uniform_real_distribution<Real> u(-1, 1), pos(0, 1);
  std::vector<Contact> out;
  for (int c = 0; c < count; ++c) {
    Contact k;
    k.input.normal = Vec3(u(rng), u(rng), u(rng)).normalized();
    k.input.overlap = 1e-5 * (0.01 + pos(rng));
    k.input.r_eff = 5e-4 * (1 + pos(rng));
    k.input.m_eff = 1e-5 * (1 + pos(rng));
    k.input.v_rel = Vec3(u(rng), u(rng), u(rng)) * 0.1;
    k.input.dt = 1e-5;
    k.input.w_rel = Vec3(u(rng), u(rng), u(rng)) * 50;
    k.input.rolling_inertia = 1e-12 * (1 + pos(rng));
    k.mi = static_cast<int>(pos(rng) * 2);
    k.mj = static_cast<int>(pos(rng) * 2);
    k.history.assign(history_size, 0.0);
    if (c % 4 != 0)
      for (Real& h : k.history) h = u(rng) * (c % 4 == 1 ? 1e-4 : 1e-7);
    if (c % 4 == 3) k.history[0] = 0;  // linear: stiffness not stored yet; EEPA: d_max 0
    if (c % 8 == 2) k.history[0] = 2e-5 * pos(rng);  // EEPA unloading (d_max > overlap)
    if (c % 16 == 5) k.history[0] = 2e3;             // linear: a stored stiffness
    out.push_back(k);
  }
  return out;
}

template <class Law>
void check_law_lanes(const Law& law, const std::string& tag, std::mt19937_64& rng) {
  constexpr int S = Law::kHistorySize;
  constexpr int W = gs::kPackLanes;
  std::vector<Contact> contacts = random_contacts(64 * W, S, rng);
  for (std::size_t first = 0; first < contacts.size(); first += W) {
    gs::ContactLanes<gs::LaneReal> lanes{};
    const typename Law::Pair* pairs[W];
    alignas(64) Real columns[S][W];
    alignas(64) Real in[15][W];
    for (int l = 0; l < W; ++l) {
      const Contact& k = contacts[first + l];
      pairs[l] = &law.pair(k.mi, k.mj);
      const Real values[15] = {k.input.normal[0],
                               k.input.normal[1],
                               k.input.normal[2],
                               k.input.overlap,
                               k.input.r_eff,
                               k.input.m_eff,
                               k.input.v_rel[0],
                               k.input.v_rel[1],
                               k.input.v_rel[2],
                               k.input.w_rel[0],
                               k.input.w_rel[1],
                               k.input.w_rel[2],
                               k.input.rolling_inertia,
                               0,
                               0};
      for (int q = 0; q < 15; ++q) in[q][l] = values[q];
      for (int s = 0; s < S; ++s) columns[s][l] = k.history[s];
    }
    auto column = [&](int q) { return gs::load_lanes<gs::LaneReal>(in[q]); };
    lanes.normal = {column(0), column(1), column(2)};
    lanes.overlap = column(3);
    lanes.r_eff = column(4);
    lanes.m_eff = column(5);
    lanes.v_rel = {column(6), column(7), column(8)};
    lanes.dt = contacts[first].input.dt;
    lanes.w_rel = {column(9), column(10), column(11)};
    lanes.rolling_inertia = column(12);
    gs::LaneReal h[S];
    for (int s = 0; s < S; ++s) h[s] = gs::load_lanes<gs::LaneReal>(columns[s]);
    gs::ContactLanesOutput<gs::LaneReal> packed;
    if constexpr (W == 1)
      packed = law.force_lanes(gs::Param<typename Law::Pair, Real>(*pairs[0]), lanes, h);
    else
      packed = law.force_lanes(gs::Param<typename Law::Pair, gs::LaneReal>::of(pairs), lanes, h);
    for (int l = 0; l < W; ++l) {
      Contact k = contacts[first + l];
      const gs::ContactOutput one = law.force(law.pair(k.mi, k.mj), k.input, k.history.data());
      const Vec3 f(gs::lane(packed.force.x, l), gs::lane(packed.force.y, l),
                   gs::lane(packed.force.z, l));
      const Vec3 m(gs::lane(packed.rolling_torque.x, l), gs::lane(packed.rolling_torque.y, l),
                   gs::lane(packed.rolling_torque.z, l));
      bool history_same = true;
      for (int s = 0; s < S; ++s)
        history_same = history_same && same_bits(gs::lane(h[s], l), k.history[s]);
      const std::string where = tag + " contact " + std::to_string(first + l);
      EXPECT(same_bits(f, one.force), where + ": packed force differs from the scalar law");
      EXPECT(same_bits(m, one.rolling_torque), where + ": packed rolling torque differs");
      EXPECT(history_same, where + ": packed history differs from the scalar law");
    }
  }
}

// A dense random packing of two materials (overlaps up to 5 % of d, list with a skin).
// big: one sphere of 5 d among them, with the smallest id, so that its row (over a hundred
// entries) spans several batches.
void make_packing(gs::ParticleStore& ps, std::mt19937_64& rng, bool big = false) {
  std::uniform_real_distribution<Real> u(-1, 1), pos(0, 1);
  const int side = 9;
  const Real d = 1e-3, spacing = 0.97 * d;
  if (big) {
    const Real r = 2.5 * d, m = 2500.0 * (4.0 / 3.0) * M_PI * r * r * r;
    ps.add_owned(-1, Vec3(4, 4, 4) * spacing, Vec3(0.01, 0, 0), Vec3(0, 5, 0), r, m,
                 0.4 * m * r * r, 1);
  }
  Index id = 0;
  for (int a = 0; a < side; ++a)
    for (int b = 0; b < side; ++b)
      for (int c = 0; c < side; ++c) {
        const Vec3 x = Vec3(a, b, c) * spacing + Vec3(u(rng), u(rng), u(rng)) * 0.02 * d;
        const Real r = 0.5 * d * (1 + 0.04 * u(rng));
        const Real m = 2500.0 * (4.0 / 3.0) * M_PI * r * r * r;
        // Scrambled ids: pairs are stored at the smaller id, so rows meet earlier rows' partners.
        const gs::GlobalId gid = (id * 7919) % (side * side * side);
        ps.add_owned(gid, x, Vec3(u(rng), u(rng), u(rng)) * 0.05, Vec3(u(rng), u(rng), u(rng)) * 20,
                     r, m, 0.4 * m * r * r, static_cast<std::int32_t>(pos(rng) * 2));
        ++id;
      }
}

// Before step `step` of a test: the particles moved back or forth (contacts open and close),
// the forces and torques reset.
void start_step(gs::ParticleStore& p, int step, Real dt) {
  for (Index i = 0; i < p.n_owned(); ++i) {
    p.position[i] += p.velocity[i] * (5 * dt) * (step % 2 ? 1 : -1);
    p.force[i] = Vec3(0, 0, -1e-6);
    p.torque[i].setZero();
  }
}

// The pair loop as one contact at a time (the reference order): row by row, f[j] at once,
// f[i] at the end of a row with entries.
template <class Law>
void reference_pair_forces(const Law& law, gs::ParticleStore& ps, gs::ContactList& list, Real dt) {
  constexpr int S = Law::kHistorySize;
  for (Index i = 0; i < ps.n_owned(); ++i) {
    const Index b = list.first[i], e = list.first[i + 1];
    if (b == e) continue;
    Vec3 fi = Vec3::Zero(), ti = Vec3::Zero();
    for (Index k = b; k < e; ++k) {
      const Index j = list.partner[k];
      Real* h = list.history.data() + static_cast<std::size_t>(k) * S;
      const Vec3 d = ps.position[i] - ps.position[j];
      const Real rsum = ps.radius[i] + ps.radius[j];
      const Real d2 = d.squaredNorm();
      if (d2 >= rsum * rsum) {
        if (list.touching[k]) std::fill(h, h + S, Real(0));
        list.touching[k] = 0;
        continue;
      }
      const Real dist = std::sqrt(d2), overlap = rsum - dist;
      // n, R*, m* and I_r as both pair loops compute them (one reciprocal for the means)
      const gs::PairMeans<Real> means = gs::pair_means<true>(
          gs::from_eigen(d), dist, ps.radius[i], ps.radius[j], rsum,
          ps.inv_mass[i] + ps.inv_mass[j], ps.inv_rolling_inertia[i] + ps.inv_rolling_inertia[j]);
      const gs::PairMeans<Real> means_no_inertia =
          gs::pair_means<false>(gs::from_eigen(d), dist, ps.radius[i], ps.radius[j], rsum,
                                ps.inv_mass[i] + ps.inv_mass[j]);
      const gs::PairMeans<Real>& m = Law::kRollingInertia ? means : means_no_inertia;
      const Vec3 n = gs::to_eigen(m.normal);
      const Real ai = ps.radius[i] - 0.5 * overlap, aj = ps.radius[j] - 0.5 * overlap;
      const Vec3 vrel = ps.velocity[i] - ps.velocity[j] -
                        (ai * ps.angular_velocity[i] + aj * ps.angular_velocity[j]).cross(n);
      gs::ContactInput c{n, overlap, m.r_eff, m.m_eff, vrel, dt};
      c.w_rel = ps.angular_velocity[i] - ps.angular_velocity[j];
      c.rolling_inertia = m.rolling_inertia;
      list.touching[k] = 1;
      const gs::ContactOutput out = law.force(law.pair(ps.material[i], ps.material[j]), c, h);
      const Vec3 nxf = n.cross(out.force);
      fi += out.force;
      ti -= ai * nxf;
      ps.force[j] -= out.force;
      ps.torque[j] -= aj * nxf;
      if constexpr (Law::kRolling) {
        ti += out.rolling_torque;
        ps.torque[j] -= out.rolling_torque;
      }
    }
    ps.force[i] += fi;
    ps.torque[i] += ti;
  }
}

template <class Law>
void check_pair_loop(const Law& law, const std::string& tag, std::mt19937_64& rng,
                     bool big = false) {
  // Two stores built alike (a copy of a ParticleStore shares its arrays).
  gs::ParticleStore ps, reference_ps;
  std::mt19937_64 twin = rng;
  make_packing(ps, rng, big);
  make_packing(reference_ps, twin, big);
  const Real skin = 1e-4;
  Real r_max = 0;
  for (Index i = 0; i < ps.n_owned(); ++i) r_max = std::max(r_max, ps.radius[i]);
  const Real cutoff = 2 * r_max + skin;
  gs::ContactList list;
  list.history_stride = Law::kHistorySize;
  gs::CellGrid grid;
  grid.build(ps.position.data(), ps.n_local(), cutoff, 1 << 20);
  gs::build_pair_list(ps, grid, cutoff, skin, list);
  if (big) EXPECT(list.first[1] - list.first[0] > 64, tag + ": a row longer than a batch");
  gs::ContactList reference = list;
  gs::ContactStats stats;
  const Real dt = 2e-6;
  // Several steps, the particles moved between them: histories develop, contacts open. The
  // forces are compared after every step (each loop's own sums).
  bool forces = true, torques = true;
  for (int step = 0; step < 6; ++step) {
    for (gs::ParticleStore* p : {&ps, &reference_ps}) start_step(*p, step, dt);
    if (step % 2)  // both loops, whatever the lane width: one by one and batched
      gs::accumulate_pair_forces_one_by_one<Law, true, false>(law, ps, list, dt, stats);
    else
      gs::accumulate_pair_forces_batched<Law, true, false>(law, ps, list, dt, stats);
    reference_pair_forces(law, reference_ps, reference, dt);
    for (Index i = 0; i < ps.n_owned(); ++i) {
      forces = forces && same_bits(ps.force[i], reference_ps.force[i]);
      torques = torques && same_bits(ps.torque[i], reference_ps.torque[i]);
    }
  }
  const bool history = same_histories(list, reference);
  EXPECT(forces, tag + ": pair loop forces differ from the one-contact loop");
  EXPECT(torques, tag + ": pair loop torques differ from the one-contact loop");
  EXPECT(history, tag + ": pair loop histories differ from the one-contact loop");
  EXPECT(list.touching == reference.touching, tag + ": touching flags differ");
}

// The wall loop as one contact at a time (the reference order), analytic walls only.
template <class Law>
void reference_wall_forces(const Law& law, gs::ParticleStore& ps, std::vector<gs::Wall>& walls,
                           gs::ContactList& list, Real dt) {
  constexpr int S = Law::kHistorySize;
  for (Index i = 0; i < ps.n_owned(); ++i)
    for (Index k = list.first[i]; k < list.first[i + 1]; ++k) {
      gs::Wall& wall = walls[list.partner[k]];
      Real* h = list.history.data() + static_cast<std::size_t>(k) * S;
      const Real ri = ps.radius[i];
      gs::WallContact g;
      if (!wall.closest(ps.position[i], g) || g.distance >= ri) {
        if (list.touching[k]) std::fill(h, h + S, Real(0));
        list.touching[k] = 0;
        continue;
      }
      const Real overlap = ri - g.distance, ai = ri - 0.5 * overlap;
      const Vec3 vrel = ps.velocity[i] - ai * ps.angular_velocity[i].cross(g.normal) -
                        wall.surface_velocity(g.point);
      gs::ContactInput c{g.normal, overlap, ri, ps.mass[i], vrel, dt};
      c.w_rel = ps.angular_velocity[i] - wall.angular_velocity;
      c.rolling_inertia = 1 / ps.inv_rolling_inertia[i];
      list.touching[k] = 1;
      const gs::ContactOutput out = law.force(law.pair(ps.material[i], wall.law_material), c, h);
      ps.force[i] += out.force;
      ps.torque[i] -= ai * g.normal.cross(out.force);
      wall.force -= out.force;
      wall.torque -= (g.point - wall.origin).cross(out.force);
      if constexpr (Law::kRolling) {
        ps.torque[i] += out.rolling_torque;
        wall.torque -= out.rolling_torque;
      }
    }
}

// The batched wall loop (contact/wall_loop.hpp) against the reference: a moving floor, a side
// plane turning about its normal, a cylinder touching the same side (three walls, two
// materials).
template <class Law>
void check_wall_loop(const Law& law, const std::string& tag, std::mt19937_64& rng) {
  gs::ParticleStore ps, reference_ps;
  std::mt19937_64 twin = rng;
  make_packing(ps, rng);
  make_packing(reference_ps, twin);
  std::vector<gs::Wall> walls(3);
  walls[0].point = Vec3(0, 0, -0.49e-3);
  walls[0].velocity = Vec3(0.02, -0.01, 0);
  walls[1].point = Vec3(-0.49e-3, 0, 0);
  walls[1].normal = Vec3::UnitX();
  walls[1].angular_velocity = Vec3(3, 0, 0);
  walls[1].origin = Vec3(0, 4e-3, 4e-3);
  walls[2].shape = gs::WallShape::Cylinder;
  walls[2].point = Vec3(-4e-3, 3.88e-3, 0);
  walls[2].axis = Vec3::UnitZ();
  walls[2].radius = 3.53e-3;
  walls[2].inside = false;
  walls[2].material = 0;
  for (gs::Wall& w : walls) w.law_material = w.material < 0 ? 2 : w.material;
  const Real skin = 1e-4;
  gs::ContactList list;
  list.history_stride = Law::kHistorySize;
  gs::build_wall_list(ps, walls, {0, 1, 2}, skin, list);
  gs::WallPrimitives prims{{0, 1, 2}, {0, 1, 2}};
  gs::ContactList reference = list;
  std::vector<gs::Wall> reference_walls = walls;
  gs::ContactStats stats;
  const Real dt = 2e-6;
  bool particles = true, loads = true;  // after every step
  for (int step = 0; step < 6; ++step) {
    for (gs::ParticleStore* p : {&ps, &reference_ps}) start_step(*p, step, dt);
    for (std::vector<gs::Wall>* ws : {&walls, &reference_walls})
      for (gs::Wall& w : *ws) w.force = w.torque = Vec3::Zero();
    gs::accumulate_wall_forces<Law, true, false>(law, ps, walls, prims, list, dt, stats);
    reference_wall_forces(law, reference_ps, reference_walls, reference, dt);
    for (Index i = 0; i < ps.n_owned(); ++i)
      particles = particles && same_bits(ps.force[i], reference_ps.force[i]) &&
                  same_bits(ps.torque[i], reference_ps.torque[i]);
    for (std::size_t w = 0; w < walls.size(); ++w)
      loads = loads && same_bits(walls[w].force, reference_walls[w].force) &&
              same_bits(walls[w].torque, reference_walls[w].torque);
  }
  bool touching = false;
  for (std::uint8_t t : list.touching) touching = touching || t;
  const bool history = same_histories(list, reference);
  EXPECT(touching, tag + ": the wall test has touching contacts");
  EXPECT(particles, tag + ": wall loop forces or torques differ from the one-contact loop");
  EXPECT(loads, tag + ": wall loads differ from the one-contact loop");
  EXPECT(history, tag + ": wall loop histories differ from the one-contact loop");
  EXPECT(list.touching == reference.touching, tag + ": wall touching flags differ");
}

template <std::size_t I = 0>
void check_every_law(std::mt19937_64& rng) {
  if constexpr (I < std::variant_size_v<gs::ContactLaw>) {
    using Law = std::variant_alternative_t<I, gs::ContactLaw>;
    for (int setting = 0; setting < 8; ++setting) {
      gs::ContactSettings s;
      s.history = setting & 1 ? gs::TangentialHistory::Incremental : gs::TangentialHistory::Total;
      s.spring_rotation = setting & 2 ? gs::SpringRotation::Project : gs::SpringRotation::Rescale;
      s.limit_force = setting & 4;
      s.tangential_damping = setting != 5;
      gs::ContactLaw law{std::in_place_index<I>, s};
      prepare(law);
      const std::string tag = Law::name() + " setting " + std::to_string(setting);
      check_law_lanes(std::get<I>(law), tag, rng);
      if (setting % 3 == 0) check_pair_loop(std::get<I>(law), tag, rng);
      if (setting == 1) check_pair_loop(std::get<I>(law), tag + " (long row)", rng, true);
      if (setting % 4 == 1) check_wall_loop(std::get<I>(law), tag, rng);
    }
    check_every_law<I + 1>(rng);
  }
}

}  // namespace

int main() {
  std::mt19937_64 rng(2026);
  check_every_law(rng);
  std::printf("contact lanes (%d per pack): %d checks, %d failed\n", gs::kPackLanes,
              test_support::g_checks, test_support::g_failures);
  return test_support::g_failures == 0 ? 0 : 1;
}
