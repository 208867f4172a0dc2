// Core invariants checked without Python: a dependency-free test executable (prints every
// failed check, returns non-zero if any failed).
//   hertz_normal_force   – head-on elastic Hertz-Mindlin contact: F = 4/3 E* sqrt(R*) delta^1.5
//                          (law alone and through accumulate_pair_forces), Newton's third law;
//   pair_list_brute      – build_pair_list equals an O(N^2) search (2000 random polydisperse
//                          1:3 particles, shuffled global ids, with and without a cell cap);
//   history_carry        – HistoryCarry save/restore keeps histories across a permutation;
//   wall_list            – build_wall_list equals the per-particle test of every wall, in
//                          order, for 40 planes (more than its bit masks hold), a rectangle
//                          and a cylinder;
//   material_validation  – MaterialTable rejects poisson_ratio 0.7 with the documented message;
//   spring_rotation      – a spring turned with its contact: "rescale" keeps the length and lies
//                          in the new tangent plane, "project" shortens it by cos(theta), and
//                          the two-vector rotation equals two single ones bit for bit;
//   page_vector          – a PageVector grown from a few values past the mapping threshold
//                          keeps its contents; its large buffers are mapped (page aligned);
//   shared_array_stagger – SharedArrays keep their contents across growth, stay aligned for
//                          their type, and large ones (huge-page ones included) start at
//                          different addresses modulo 4 KiB.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "contact/contact_input.hpp"
#include "contact/contact_law.hpp"
#include "contact/contact_model.hpp"
#include "contact/contact_stats.hpp"
#include "contact/interaction.hpp"
#include "contact/pair_loop.hpp"
#include "contact/tangential_models.hpp"
#include "core/errors.hpp"
#include "core/page_vector.hpp"
#include "neighbor/cell_grid.hpp"
#include "neighbor/contact_history.hpp"
#include "neighbor/neighbor_list.hpp"
#include "state/material_table.hpp"
#include "state/particle_store.hpp"

namespace gs = grainscale;
using gs::GlobalId;
using gs::Index;
using gs::Real;
using gs::Vec3;

namespace {

int g_failures = 0;
int g_checks = 0;
const char* g_test = "";

void check(bool ok, const std::string& what, int line) {
  ++g_checks;
  if (ok) return;
  ++g_failures;
  std::printf("FAIL [%s] test_core.cpp:%d: %s\n", g_test, line, what.c_str());
}
#define CHECK(cond, what) check((cond), (what), __LINE__)

std::string str(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

bool close_rel(Real a, Real b, Real rel) { return std::abs(a - b) <= rel * std::abs(b); }

const gs::MaterialProperties kGlass{2500.0, 1e7, 0.3};

// Hertz-Mindlin with LIGGGHTS-type damping and no rolling resistance (the default law).
using HertzMindlin = gs::ContactModel<gs::HertzNormal, gs::HertzDamping, gs::NoRolling>;

// The same interaction (restitution e, friction 0.5) for every material pair, walls included.
std::vector<gs::Interaction> interactions(const gs::MaterialTable& materials, Real e) {
  gs::Interaction in;
  in.restitution = e;
  in.friction = 0.5;
  const std::size_t stride = materials.n_materials() + 1;
  return std::vector<gs::Interaction>(stride * stride, in);
}

void add_particle(gs::ParticleStore& ps, GlobalId id, const Vec3& x, Real r,
                  const Vec3& v = Vec3::Zero()) {
  const Real m = kGlass.density * (4.0 / 3.0) * M_PI * r * r * r;
  ps.add_owned(id, x, v, Vec3::Zero(), r, m, 0.4 * m * r * r, 0);
}

// Cells of cell_fraction x the cut-off (the pair list widens its stencil for small cells).
void build_list(const gs::ParticleStore& ps, Real skin, std::size_t max_cells,
                gs::ContactList& list, Real cell_fraction = 1) {
  Real r_max = 0;
  for (Index i = 0; i < ps.n_owned(); ++i) r_max = std::max(r_max, ps.radius[i]);
  gs::CellGrid grid;
  grid.build(ps.position.data(), ps.n_local(), cell_fraction * (2 * r_max + skin), max_cells);
  gs::build_pair_list(ps, grid, 2 * r_max + skin, skin, list);
}

// ---------------------------------------------------------------------------------------------
void test_hertz_normal_force() {
  g_test = "hertz_normal_force";
  gs::MaterialTable materials;
  materials.add(kGlass);
  CHECK(std::holds_alternative<HertzMindlin>(
            gs::make_contact_law("hertz", "none", gs::ContactSettings{})),
        "make_contact_law(\"hertz\", \"none\") is not the law tested here");
  HertzMindlin law{gs::ContactSettings{}};
  law.prepare(materials, interactions(materials, 1.0));  // e = 1: no normal or tangential damping
  const Real nu = kGlass.poisson_ratio, E = kGlass.youngs_modulus;
  const Real e_star = 1 / (2 * (1 - nu * nu) / E);
  CHECK(close_rel(law.pair(0, 0).normal.effective_youngs, e_star, 1e-14),
        "E* = " + str(law.pair(0, 0).normal.effective_youngs) + ", expected " + str(e_star));
  CHECK(law.pair(0, 0).damping == 0, "damping for e = 1 is " + str(law.pair(0, 0).damping));

  const Real r1 = 1e-3, r2 = 2e-3;
  const Real r_eff = r1 * r2 / (r1 + r2);
  const Vec3 n = Vec3(1, 2, -2) / 3;  // unit normal from j to i
  for (Real delta : {1e-6, 1e-5, 3e-5, 1e-4}) {
    const Real expected = (4.0 / 3.0) * e_star * std::sqrt(r_eff) * std::pow(delta, 1.5);
    // The law alone, at rest and approaching head-on (no damping at e = 1, no tangential part).
    for (Real vn : {0.0, -0.3, 0.2}) {
      Real history[3] = {0, 0, 0};
      const gs::ContactInput c{n, delta, r_eff, 1e-5, vn * n, 1e-6};
      const Vec3 f = law.force(law.pair(0, 0), c, history).force;
      const std::string tag = "delta=" + str(delta) + " vn=" + str(vn);
      CHECK(close_rel(f.dot(n), expected, 1e-12),
            tag + ": F.n = " + str(f.dot(n)) + ", expected " + str(expected));
      CHECK((f - f.dot(n) * n).norm() <= 1e-12 * expected,
            tag + ": tangential force " + str((f - f.dot(n) * n).norm()) + " on a head-on contact");
      // Only round-off of the normal's components can leave a tangential velocity.
      CHECK(Eigen::Map<Vec3>(history).norm() <= 1e-12 * std::abs(vn) * c.dt,
            tag + ": head-on contact loaded the tangential spring");
    }
    // Through the pair loop: two spheres along n (particle 0 is i: smaller global id).
    gs::ParticleStore ps;
    const Vec3 x1(0.1, -0.2, 0.3);
    add_particle(ps, 0, x1 + (r1 + r2 - delta) * n, r1, -0.1 * n);
    add_particle(ps, 1, x1, r2, 0.1 * n);
    gs::ContactList list;
    list.history_stride = HertzMindlin::kHistorySize;
    build_list(ps, 1e-4, 64, list);
    CHECK(list.size() == 1, "pair list of two touching spheres has " + std::to_string(list.size()) +
                                " entries, expected 1");
    if (list.size() != 1) continue;
    for (Index i = 0; i < 2; ++i) {
      ps.force[i].setZero();
      ps.torque[i].setZero();
    }
    gs::ContactStats stats;
    gs::accumulate_pair_forces<HertzMindlin, true, true>(law, ps, list, 1e-6, stats);
    const Real overlap = (r1 + r2) - (ps.position[0] - ps.position[1]).norm();
    const Real expected_loop = (4.0 / 3.0) * e_star * std::sqrt(r_eff) * std::pow(overlap, 1.5);
    const std::string tag = "pair loop delta=" + str(delta);
    CHECK(close_rel(overlap, delta, 1e-9), tag + ": overlap " + str(overlap));
    CHECK(close_rel(ps.force[0].dot(n), expected_loop, 1e-12),
          tag + ": F.n = " + str(ps.force[0].dot(n)) + ", expected " + str(expected_loop));
    CHECK(close_rel(ps.force[0].dot(n), expected, 1e-9),
          tag + ": F.n = " + str(ps.force[0].dot(n)) + " vs nominal " + str(expected));
    CHECK((ps.force[0] + ps.force[1]).norm() == 0, tag + ": forces on i and j do not cancel");
    CHECK(ps.torque[0].norm() <= 1e-12 * expected * r1 &&
              ps.torque[1].norm() <= 1e-12 * expected * r2,
          tag + ": head-on contact produced a torque");
    CHECK(stats.contacts == 1, tag + ": stats.contacts = " + std::to_string(stats.contacts));
  }
}

// ---------------------------------------------------------------------------------------------
void random_poly_store(gs::ParticleStore& ps, Index n, Real r_min, Real box, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<Real> ux(0, box), ur(r_min, 3 * r_min);
  std::vector<GlobalId> ids(n);
  std::iota(ids.begin(), ids.end(), GlobalId(100));
  std::shuffle(ids.begin(), ids.end(), rng);  // id order unrelated to index or position
  for (Index k = 0; k < n; ++k) {
    const Vec3 x(ux(rng), ux(rng), ux(rng));
    add_particle(ps, ids[k], x, ur(rng));
  }
}

using PairSet = std::set<std::pair<GlobalId, GlobalId>>;

PairSet brute_force_pairs(const gs::ParticleStore& ps, Real skin) {
  PairSet out;
  for (Index i = 0; i < ps.n_owned(); ++i)
    for (Index j = i + 1; j < ps.n_owned(); ++j) {
      const Real cut = ps.radius[i] + ps.radius[j] + skin;
      if ((ps.position[i] - ps.position[j]).squaredNorm() < cut * cut)
        out.insert({std::min(ps.id[i], ps.id[j]), std::max(ps.id[i], ps.id[j])});
    }
  return out;
}

void test_pair_list_brute() {
  g_test = "pair_list_brute";
  const Index n = 2000;
  const Real r_min = 1e-3, skin = 0.2e-3;
  // Dense (solid fraction ~0.5, overlaps allowed) and sparse (~0.025) boxes.
  for (Real box : {0.055, 0.15}) {
    gs::ParticleStore ps;
    random_poly_store(ps, n, r_min, box, 4242);
    const PairSet expected = brute_force_pairs(ps, skin);
    CHECK(expected.size() > static_cast<std::size_t>(box < 0.1 ? n : 50),
          "too few pairs for a meaningful test: " + std::to_string(expected.size()));
    // Cells of the cut-off, of half of it (as Level uses) and of 0.3 of it (4 cells of reach);
    // a generous cap and a tiny cap that forces enlarged cells.
    for (Real fraction : {1.0, 0.5, 0.3})
      for (std::size_t max_cells : {std::size_t(16 * n + 64), std::size_t(7)}) {
        const std::string tag = "box=" + str(box) + " cells=" + str(fraction) +
                                " x cut-off, max_cells=" + std::to_string(max_cells);
        gs::ContactList list;
        list.history_stride = 3;
        build_list(ps, skin, max_cells, list, fraction);
        CHECK(list.first.size() == static_cast<std::size_t>(n) + 1 && list.first[0] == 0 &&
                  list.first[n] == static_cast<Index>(list.size()),
              tag + ": malformed CSR offsets");
        CHECK(list.history.size() == 3 * list.size(), tag + ": history size");
        CHECK(list.owner.size() == list.size(), tag + ": owner size");
        PairSet got;
        bool oriented = true, sorted_offsets = true, owned = true;
        std::size_t duplicates = 0;
        for (Index i = 0; i < n; ++i) {
          sorted_offsets = sorted_offsets && list.first[i] <= list.first[i + 1];
          for (Index k = list.first[i]; k < list.first[i + 1]; ++k) {
            owned = owned && list.owner[k] == i;
            const Index j = list.partner[k];
            oriented = oriented && ps.id[i] < ps.id[j];
            if (!got.insert({std::min(ps.id[i], ps.id[j]), std::max(ps.id[i], ps.id[j])}).second)
              ++duplicates;
          }
        }
        CHECK(sorted_offsets, tag + ": offsets not monotonic");
        CHECK(owned, tag + ": an entry's owner is not its row");
        CHECK(oriented, tag + ": an entry is not stored at the particle with the smaller id");
        CHECK(duplicates == 0, tag + ": " + std::to_string(duplicates) + " duplicate entries");
        std::size_t missing = 0, extra = 0;
        for (const auto& p : expected) missing += got.count(p) == 0;
        for (const auto& p : got) extra += expected.count(p) == 0;
        CHECK(missing == 0 && extra == 0,
              tag + ": list has " + std::to_string(got.size()) + " pairs, brute force " +
                  std::to_string(expected.size()) + " (" + std::to_string(missing) + " missing, " +
                  std::to_string(extra) + " extra)");
      }
  }
}

// Ghosts: the pairs of the owned particles with each other and with ghosts, each stored at the
// particle with the smaller id, and none whose smaller id is a ghost's (that pair is stored by
// the ghost's owner on its own rank).
void test_pair_list_with_ghosts() {
  g_test = "pair_list_with_ghosts";
  const Index n_all = 2000, n_owned = 1500;
  const Real r_min = 1e-3, skin = 0.2e-3;
  gs::ParticleStore all;
  random_poly_store(all, n_all, r_min, 0.055, 77);
  gs::ParticleStore ps;
  for (Index i = 0; i < n_owned; ++i) add_particle(ps, all.id[i], all.position[i], all.radius[i]);
  const Index first = ps.add_ghost_slots(n_all - n_owned);
  for (Index g = 0; g < n_all - n_owned; ++g) {
    ps.position[first + g] = all.position[n_owned + g];
    ps.radius[first + g] = all.radius[n_owned + g];
    ps.id[first + g] = all.id[n_owned + g];
  }
  PairSet expected;
  std::size_t with_ghost = 0;
  for (Index i = 0; i < n_all; ++i)
    for (Index j = i + 1; j < n_all; ++j) {
      const Real cut = ps.radius[i] + ps.radius[j] + skin;
      if (!((ps.position[i] - ps.position[j]).squaredNorm() < cut * cut)) continue;
      const Index smaller = ps.id[i] < ps.id[j] ? i : j;
      if (smaller >= n_owned) continue;
      expected.insert({std::min(ps.id[i], ps.id[j]), std::max(ps.id[i], ps.id[j])});
      with_ghost += std::max(i, j) >= n_owned;
    }
  CHECK(with_ghost > 100, "too few owned-ghost pairs: " + std::to_string(with_ghost));
  for (Real fraction : {1.0, 0.5}) {
    gs::ContactList list;
    list.history_stride = 3;
    build_list(ps, skin, std::size_t(16 * n_all + 64), list, fraction);
    PairSet got;
    bool oriented = true;
    for (Index i = 0; i < n_owned; ++i)
      for (Index k = list.first[i]; k < list.first[i + 1]; ++k) {
        const Index j = list.partner[k];
        oriented = oriented && ps.id[i] < ps.id[j];
        got.insert({std::min(ps.id[i], ps.id[j]), std::max(ps.id[i], ps.id[j])});
      }
    const std::string tag = "cells=" + str(fraction) + " x cut-off";
    CHECK(oriented, tag + ": an entry is not stored at the particle with the smaller id");
    CHECK(got == expected && list.size() == expected.size(),
          tag + ": list has " + std::to_string(list.size()) + " entries, expected " +
              std::to_string(expected.size()));
  }
}

// ---------------------------------------------------------------------------------------------
// Histories are produced by the force loop itself (random velocities and spins on a static,
// overlapping packing), so the test does not depend on how the list marks touching entries.
void test_wall_list() {
  const Index n = 3000;
  const Real skin = 0.2e-3;
  gs::ParticleStore ps;
  random_poly_store(ps, n, 1e-3, 0.05, 777);
  std::vector<gs::Wall> walls;
  std::mt19937 rng(99);
  std::uniform_real_distribution<Real> u(-1, 1);
  for (int w = 0; w < 40; ++w) {  // planes through the box, in random directions
    gs::Wall plane;
    plane.point = Vec3(0.025, 0.025, 0.025) + 0.02 * Vec3(u(rng), u(rng), u(rng));
    plane.normal = Vec3(u(rng), u(rng), u(rng)).normalized();
    walls.push_back(plane);
  }
  gs::Wall rectangle;
  rectangle.shape = gs::WallShape::Rectangle;
  rectangle.point = Vec3(0.01, 0.01, 0.02);
  rectangle.edge1 = Vec3(0.03, 0, 0);
  rectangle.edge2 = Vec3(0, 0.03, 0.005);
  rectangle.normal = rectangle.edge1.cross(rectangle.edge2).normalized();
  walls.insert(walls.begin() + 3, rectangle);
  gs::Wall cylinder;
  cylinder.shape = gs::WallShape::Cylinder;
  cylinder.point = Vec3(0.025, 0.025, 0);
  cylinder.radius = 0.02;
  cylinder.length = 0.04;
  walls.insert(walls.begin() + 35, cylinder);
  std::vector<Index> primitive_first(walls.size());
  std::iota(primitive_first.begin(), primitive_first.end(), Index(0));
  gs::ContactList list;
  list.history_stride = 3;
  gs::build_wall_list(ps, walls, primitive_first, skin, list);
  std::vector<Index> expected;
  std::size_t wrong_rows = 0;
  for (Index i = 0; i < n; ++i) {
    expected.clear();
    for (std::size_t w = 0; w < walls.size(); ++w) {
      gs::WallContact c;
      if (walls[w].closest(ps.position[i], c) && c.distance < ps.radius[i] + skin)
        expected.push_back(static_cast<Index>(w));
    }
    const std::vector<Index> got(list.partner.begin() + list.first[i],
                                 list.partner.begin() + list.first[i + 1]);
    wrong_rows += got != expected;
  }
  CHECK(list.size() > static_cast<std::size_t>(n), "too few wall entries for a meaningful test");
  CHECK(wrong_rows == 0, std::to_string(wrong_rows) + " rows differ from the per-wall test");
  CHECK(list.owner.size() == list.size() && list.history.size() == 3 * list.size(),
        "index and history sized");
}

void test_history_carry() {
  g_test = "history_carry";
  const Index n = 500;
  const Real skin = 0.2e-3, dt = 1e-5;
  const int stride = HertzMindlin::kHistorySize;
  gs::ParticleStore ps;
  random_poly_store(ps, n, 1e-3, 0.035, 99);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<Real> u(-1, 1);
  for (Index i = 0; i < n; ++i) {
    ps.velocity[i] = 1e-3 * Vec3(u(rng), u(rng), u(rng));
    ps.angular_velocity[i] = Vec3(u(rng), u(rng), u(rng));
  }
  gs::MaterialTable materials;
  materials.add(kGlass);
  HertzMindlin law{gs::ContactSettings{}};
  law.prepare(materials, interactions(materials, 0.5));

  gs::ContactList list;
  list.history_stride = stride;
  build_list(ps, skin, 2 * n + 64, list);
  gs::ContactStats stats;
  for (int s = 0; s < 3; ++s)
    gs::accumulate_pair_forces<HertzMindlin, true, false>(law, ps, list, dt, stats);

  // Expected state per (owner id, partner id): its history if non-zero (a touching contact).
  std::map<std::pair<GlobalId, GlobalId>, std::vector<Real>> saved;
  std::size_t n_touching = 0;
  std::vector<GlobalId> keys(list.size());
  for (Index i = 0; i < n; ++i)
    for (Index k = list.first[i]; k < list.first[i + 1]; ++k) {
      keys[k] = ps.id[list.partner[k]];
      const Real* h = list.history.data() + static_cast<std::size_t>(k) * stride;
      std::vector<Real> value(h, h + stride);
      const bool touching = std::any_of(h, h + stride, [](Real v) { return v != 0; });
      n_touching += touching;
      saved[{ps.id[i], keys[k]}] = touching ? value : std::vector<Real>(stride, 0.0);
    }
  CHECK(n_touching > static_cast<std::size_t>(n) / 4 && n_touching < list.size(),
        "test set-up: " + std::to_string(n_touching) + " touching of " +
            std::to_string(list.size()) + " entries");
  gs::HistoryCarry carry;
  carry.save(list, gs::PartnerKey{ps.id.data()});
  CHECK(carry.size() == n_touching, "saved " + std::to_string(carry.size()) +
                                        " histories, expected the " + std::to_string(n_touching) +
                                        " touching ones");

  // Permute the particles, then add one new particle overlapping particle 0.
  std::vector<Index> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), rng);
  ps.select_owned(order);
  std::vector<Index> origin(order.begin(), order.end());
  const GlobalId new_id = 1;  // smaller than every other id: owns all of its pairs
  add_particle(ps, new_id, ps.position[0] + Vec3(1e-4, 0, 0), 1e-3);
  origin.push_back(-1);

  gs::ContactList rebuilt;
  rebuilt.history_stride = stride;
  build_list(ps, skin, 2 * ps.n_owned() + 64, rebuilt);
  std::vector<GlobalId> new_keys(rebuilt.size());
  for (std::size_t k = 0; k < rebuilt.size(); ++k) new_keys[k] = ps.id[rebuilt.partner[k]];
  carry.restore(origin, gs::PartnerKey{ps.id.data()}, rebuilt);

  std::size_t wrong = 0, restored = 0, new_pairs = 0;
  for (Index i = 0; i < ps.n_owned(); ++i)
    for (Index k = rebuilt.first[i]; k < rebuilt.first[i + 1]; ++k) {
      const GlobalId a = ps.id[i], b = new_keys[k];
      const auto it = saved.find({a, b});
      const std::vector<Real> want =
          it == saved.end() ? std::vector<Real>(stride, 0.0) : it->second;
      new_pairs += it == saved.end();
      restored += std::any_of(want.begin(), want.end(), [](Real v) { return v != 0; });
      for (int s = 0; s < stride; ++s) {
        const Real h = rebuilt.history[static_cast<std::size_t>(k) * stride + s];
        if (h != want[s]) {
          if (wrong < 5)
            std::printf("  entry (%lld, %lld) slot %d: %.17g, expected %.17g\n",
                        static_cast<long long>(a), static_cast<long long>(b), s, h, want[s]);
          ++wrong;
        }
      }
    }
  CHECK(rebuilt.size() == list.size() + new_pairs,
        "rebuilt list has " + std::to_string(rebuilt.size()) + " entries, expected " +
            std::to_string(list.size() + new_pairs));
  CHECK(wrong == 0, std::to_string(wrong) + " history values wrong after the permutation");
  CHECK(restored == n_touching,
        "restored " + std::to_string(restored) + " histories, saved " + std::to_string(n_touching));
  CHECK(new_pairs > 0, "test set-up: the added particle has no pairs");
}

// ---------------------------------------------------------------------------------------------
void test_material_validation() {
  g_test = "material_validation";
  const std::string expected = "Material.poisson_ratio must be in [0, 0.5), got 0.7";
  gs::MaterialTable table;
  try {
    table.add({2500.0, 1e7, 0.7});
    CHECK(false, "poisson_ratio 0.7 was accepted");
  } catch (const gs::InvalidArgument& e) {
    CHECK(std::string(e.what()).find(expected) != std::string::npos,
          "message \"" + std::string(e.what()) + "\" does not contain \"" + expected + "\"");
  } catch (const std::exception& e) {
    CHECK(false, std::string("wrong exception type, message: ") + e.what());
  }
  CHECK(table.n_materials() == 0, "a rejected material was added");
  bool rejected_half = false;
  try {
    table.add({2500.0, 1e7, 0.5});
  } catch (const gs::InvalidArgument&) {
    rejected_half = true;
  }
  CHECK(rejected_half, "poisson_ratio 0.5 was accepted");
  bool accepted_zero = true;
  try {
    table.add({2500.0, 1e7, 0.0});
  } catch (const std::exception&) {
    accepted_zero = false;
  }
  CHECK(accepted_zero && table.n_materials() == 1, "poisson_ratio 0 was rejected");
}

void test_spring_rotation() {
  g_test = "spring_rotation";
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<Real> u(-1, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 n0 = Vec3(u(rng), u(rng), u(rng)).normalized();
    // A spring in the old tangent plane and a new normal turned by theta.
    const Vec3 s0 = (Vec3(u(rng), u(rng), u(rng)).cross(n0)) * (1e-6 * (1 + trial));
    const Real theta = 1e-4 * (1 + trial % 50);
    const Vec3 axis = Vec3(u(rng), u(rng), u(rng)).normalized();
    const Vec3 n = Eigen::AngleAxis<Real>(theta, axis) * n0;
    gs::LaneVec<Real> a = gs::from_eigen(s0), p = a;
    gs::rotate_into_tangent_plane(a, gs::from_eigen(n));
    const Vec3 rotated = gs::to_eigen(a);
    CHECK(std::abs(rotated.norm() / s0.norm() - 1) < 1e-14, "rescale changed the length");
    CHECK(std::abs(rotated.dot(n)) < 1e-14 * s0.norm(), "rescaled spring not in the tangent plane");
    gs::project_onto_tangent_plane(p, gs::from_eigen(n));
    const Vec3 projected = gs::to_eigen(p);
    const Real expected = std::sqrt(1 - std::pow(s0.normalized().dot(n), 2));
    CHECK(std::abs(projected.norm() / s0.norm() - expected) < 1e-12,
          "projection length not |s| cos");
    CHECK(std::abs(projected.dot(n)) < 1e-14 * s0.norm(),
          "projected spring not in the tangent plane");
  }
}

void test_page_vector() {
  gs::PageVector<double> v;
  bool kept = true;
  for (int k = 0; k < 200000; ++k) {
    v.push_back(0.5 * k);
    if ((k & (k + 1)) == 0)  // after every growth step: the contents so far
      for (int m = 0; m <= k; ++m) kept = kept && v[m] == 0.5 * m;
  }
  CHECK(kept, "contents kept across growth");
  CHECK(v.size() == 200000 && v.back() == 0.5 * 199999, "size and last value");
  CHECK(reinterpret_cast<std::uintptr_t>(v.data()) % 4096 == 0,
        "a buffer above the threshold is mapped (page aligned)");
  v.assign(3, 1.0);  // shrinking keeps the buffer; a copy takes the ordinary allocator
  const gs::PageVector<double> small(v.begin(), v.end());
  CHECK(small.size() == 3 && small[2] == 1.0, "small copy");
}

void test_shared_array_stagger() {
  // Five particle arrays of 200k Vec3 (4.8 MB: 2 MiB-aligned huge-page blocks) and five of
  // 1000 (24 kB), grown from empty in step, as ParticleStore::resize_all grows its arrays.
  for (const std::size_t n : {std::size_t(200000), std::size_t(1000)}) {
    std::vector<gs::SharedArray<Vec3>> arrays(5);
    for (std::size_t k = 0; k < n; ++k)
      for (gs::SharedArray<Vec3>& a : arrays) a.push_back(Vec3::Constant(static_cast<Real>(k)));
    std::set<std::uintptr_t> offsets;
    bool kept = true, aligned = true;
    for (gs::SharedArray<Vec3>& a : arrays) {
      for (std::size_t k = 0; k < n; k += 997) kept = kept && a[k][2] == static_cast<Real>(k);
      const auto address = reinterpret_cast<std::uintptr_t>(a.data());
      aligned = aligned && address % 64 == 0;
      offsets.insert(address % 4096);
    }
    CHECK(kept, "contents kept across growth");
    CHECK(aligned, "large buffers 64-byte aligned");
    CHECK(offsets.size() == arrays.size(), "large buffers start at different offsets mod 4 KiB");
  }
  gs::SharedArray<std::int32_t> small;
  small.resize(3, 7);
  CHECK(small.size() == 3 && small[2] == 7, "small array");
}

}  // namespace

int main() {
  const std::pair<const char*, void (*)()> tests[] = {
      {"hertz_normal_force", test_hertz_normal_force},
      {"pair_list_brute", test_pair_list_brute},
      {"pair_list_with_ghosts", test_pair_list_with_ghosts},
      {"history_carry", test_history_carry},
      {"wall_list", test_wall_list},
      {"material_validation", test_material_validation},
      {"spring_rotation", test_spring_rotation},
      {"page_vector", test_page_vector},
      {"shared_array_stagger", test_shared_array_stagger},
  };
  for (const auto& [name, fn] : tests) {
    const int before = g_failures;
    g_test = name;
    try {
      fn();
    } catch (const std::exception& e) {
      check(false, std::string("unexpected exception: ") + e.what(), __LINE__);
    }
    std::printf("%-20s %s\n", name, g_failures == before ? "ok" : "FAILED");
  }
  std::printf("%d checks, %d failed\n", g_checks, g_failures);
  return g_failures == 0 ? 0 : 1;
}
