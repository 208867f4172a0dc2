// Wall avoidance of insertion, checked against brute force (prints every failed check, returns
// non-zero if any failed):
//   clear_matches_brute_force – WallClearance::clear equals the contact test evaluated on every
//                               wall and every triangle (planes, rectangle, finite and infinite
//                               cylinders, a mesh seen through its bins);
//   blocks_is_sound           – whenever blocks(c, reach, r) lets a voxel sampler drop the ball
//                               (c, reach), no centre in that ball is clear by brute force
//                               (sampled);
//   bins_box_query            – TriangleBins::candidates(lo, hi) holds every triangle whose
//                               bounding box meets the box, sorted and once.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "expect.hpp"
#include "geometry/triangle_bins.hpp"
#include "geometry/wall.hpp"
#include "insert/wall_clearance.hpp"

namespace gs = grainscale;
using gs::Real;
using gs::Vec3;

namespace {

using test_support::g_checks;
using test_support::g_failures;

std::mt19937_64 g_rng(12345);
Real uniform(Real a, Real b) { return std::uniform_real_distribution<Real>(a, b)(g_rng); }
Vec3 uniform_in(const Vec3& lo, const Vec3& hi) {
  return Vec3(uniform(lo[0], hi[0]), uniform(lo[1], hi[1]), uniform(lo[2], hi[2]));
}
Vec3 in_ball(const Vec3& c, Real radius) {
  for (;;) {
    const Vec3 u(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
    if (u.squaredNorm() <= 1) return c + radius * u;
  }
}

// A closed, finely triangulated box [lo, hi] (n x n quads per face).
std::shared_ptr<gs::TriangleMesh> box_mesh(const Vec3& lo, const Vec3& hi, int n) {
  auto m = std::make_shared<gs::TriangleMesh>();
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      const int base = static_cast<int>(m->vertices.size());
      for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
          Vec3 p;
          p[axis] = side ? hi[axis] : lo[axis];
          p[u] = lo[u] + (hi[u] - lo[u]) * i / n;
          p[v] = lo[v] + (hi[v] - lo[v]) * j / n;
          m->vertices.push_back(p);
        }
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          const int a = base + i * (n + 1) + j, b = a + n + 1;
          m->triangles.push_back({a, b, b + 1});
          m->triangles.push_back({a, b + 1, a + 1});
        }
    }
  return m;
}

std::vector<gs::Wall> walls() {
  std::vector<gs::Wall> w(6);
  w[0].shape = gs::WallShape::Plane;
  w[0].point = Vec3(0, 0, -0.8);
  w[0].normal = Vec3(0.2, 0.1, 1).normalized();
  w[1].shape = gs::WallShape::Rectangle;
  w[1].point = Vec3(-0.5, 0.3, -0.5);
  w[1].edge1 = Vec3(1.0, 0, 0.2);
  w[1].edge2 = Vec3(0, 0.1, 0.9);
  w[2].shape = gs::WallShape::Cylinder;  // finite, open ends, particles inside
  w[2].point = Vec3(0.2, -0.3, -0.4);
  w[2].axis = Vec3(0, 0.3, 1).normalized();
  w[2].radius = 0.35;
  w[2].length = 0.6;
  w[3].shape = gs::WallShape::Cylinder;  // infinite, particles outside
  w[3].point = Vec3(-0.6, -0.6, 0);
  w[3].axis = Vec3(1, 0, 0);
  w[3].radius = 0.15;
  w[3].inside = false;
  w[4].shape = gs::WallShape::Mesh;
  w[4].mesh = box_mesh(Vec3(0.3, 0.3, 0.3), Vec3(0.7, 0.6, 0.9), 6);
  w[5].shape = gs::WallShape::Mesh;  // entirely outside the placement box: left out
  w[5].mesh = box_mesh(Vec3(5, 5, 5), Vec3(6, 6, 6), 1);
  return w;
}

// The contact test of contact/wall_loop.hpp, on every wall and every triangle.
bool clear_brute(const std::vector<gs::Wall>& ws, const Vec3& x, Real r) {
  for (const gs::Wall& w : ws) {
    if (w.shape == gs::WallShape::Mesh) {
      for (int t = 0; t < static_cast<int>(w.mesh->triangles.size()); ++t)
        if ((x - w.mesh->closest(t, x).point).squaredNorm() < r * r) return false;
    } else {
      gs::WallContact g;
      if (w.closest(x, g) && g.distance < r) return false;
    }
  }
  return true;
}

const Vec3 kLo(-1, -1, -1), kHi(1, 1, 1);
const Real kMaxRadius = 0.3;

void test_clear_matches_brute_force() {
  const std::vector<gs::Wall> ws = walls();
  const gs::WallClearance clearance(ws, kLo, kHi, kMaxRadius);
  int clear = 0, touching = 0, wrong = 0;
  for (int k = 0; k < 20000; ++k) {
    const Vec3 x = uniform_in(kLo, kHi);
    const Real r = uniform(0.01, kMaxRadius);
    const bool expected = clear_brute(ws, x, r);
    if (clearance.clear(x, r) != expected) ++wrong;
    (expected ? clear : touching) += 1;
  }
  EXPECT(wrong == 0, std::to_string(wrong) + " of 20000 disagree with brute force");
  EXPECT(clear > 1000 && touching > 1000,
         "set-up: " + std::to_string(clear) + " clear, " + std::to_string(touching) + " touching");
}

void test_blocks_is_sound() {
  const std::vector<gs::Wall> ws = walls();
  const gs::WallClearance clearance(ws, kLo, kHi, kMaxRadius);
  int blocked = 0, unsound = 0;
  for (int k = 0; k < 5000; ++k) {
    const Vec3 c = uniform_in(kLo, kHi);
    const Real r = uniform(0.05, kMaxRadius);
    const Real reach = uniform(0, r);
    if (!clearance.blocks(c, reach, r)) continue;
    ++blocked;
    for (int s = 0; s < 10; ++s) {
      const Vec3 p = in_ball(c, reach);
      if (clear_brute(ws, p, r)) ++unsound;
    }
  }
  EXPECT(unsound == 0, std::to_string(unsound) + " clear centres inside blocked balls");
  EXPECT(blocked > 500, "set-up: only " + std::to_string(blocked) + " balls blocked");
}

void test_bins_box_query() {
  const auto mesh = box_mesh(Vec3(-1, -0.5, 0), Vec3(1, 0.5, 0.4), 10);
  gs::TriangleBins bins;
  bins.build(mesh->vertices, mesh->triangles, {}, 0, 0);
  std::vector<int> got;
  int missing = 0, unsorted = 0;
  for (int k = 0; k < 2000; ++k) {
    const Vec3 c = uniform_in(Vec3(-1.3, -0.8, -0.3), Vec3(1.3, 0.8, 0.7));
    const Vec3 half(uniform(0, 0.3), uniform(0, 0.3), uniform(0, 0.3));
    bins.candidates(c - half, c + half, got);
    if (!std::is_sorted(got.begin(), got.end()) ||
        std::adjacent_find(got.begin(), got.end()) != got.end())
      ++unsorted;
    for (int t = 0; t < static_cast<int>(mesh->triangles.size()); ++t) {
      Vec3 tlo = mesh->vertices[mesh->triangles[t][0]], thi = tlo;
      for (int v : mesh->triangles[t]) {
        tlo = tlo.cwiseMin(mesh->vertices[v]);
        thi = thi.cwiseMax(mesh->vertices[v]);
      }
      const bool meets =
          ((thi - (c - half)).array() >= 0).all() && ((c + half - tlo).array() >= 0).all();
      if (meets && !std::binary_search(got.begin(), got.end(), t)) ++missing;
    }
  }
  EXPECT(missing == 0, std::to_string(missing) + " triangles missing from box queries");
  EXPECT(unsorted == 0, std::to_string(unsorted) + " box queries not sorted and unique");
}

}  // namespace

int main() {
  test_clear_matches_brute_force();
  test_blocks_is_sound();
  test_bins_box_query();
  std::printf("%d checks, %d failed\n", g_checks, g_failures);
  return g_failures == 0 ? 0 : 1;
}
