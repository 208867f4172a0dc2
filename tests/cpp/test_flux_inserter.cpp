// The flux inserter of a hierarchy's interface face (prints every failed check, returns non-zero
// if any failed):
//   carries_a_dense_inflow – owed far more than its shell holds, one place() fills the shell of a
//                            face 3.75 grain diameters across, under a parent bed of twice the
//                            grain size (simple cubic, solid fraction 0.52), to a random packing:
//                            no overlaps, every centre over the face rectangle and inside the
//                            shell's depth, grains straddling the rectangle's edges, and a solid
//                            fraction of the shell (face area x depth) of at least 0.35 (0.41
//                            measured; whole grains inside the rectangle gave 0.28);
//   books_stay_exact        – fed = inserted + pending after placement, what waits is booked;
//   stays_in_the_domain     – where the face's band reaches past a closed side of the domain (the
//                            band is widened past the face's edges), no centre is placed
//                            outside it; along a periodic axis the side does not stop placement;
//   goes_where_the_parent_reaches – with a wall across the shell and the parent's bed on one
//                            side of it, nothing goes to the other side (free of particles and
//                            clear of the wall, but out of the parent's reach); without parent
//                            particles nothing is placed (what is owed waits);
//   segments_cross_walls    – the line-of-sight test against a plane, a rectangle, a finite
//                            cylinder and a triangle.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "coupling/flux_inserter.hpp"
#include "expect.hpp"
#include "field/exchange_grid.hpp"
#include "geometry/segment_crossing.hpp"
#include "insert/occupancy_grid.hpp"
#include "insert/placement.hpp"
#include "insert/random.hpp"
#include "insert/region.hpp"
#include "insert/size_distribution.hpp"
#include "insert/wall_clearance.hpp"
#include "state/domain.hpp"

namespace gs = grainscale;
using gs::Real;
using gs::Vec3;

namespace {

constexpr Real kRadius = 1e-3;     // m, grains of d = 2 mm
constexpr Real kEdge = 7.5e-3;     // m, exchange cell edge
constexpr Real kDensity = 2500.0;  // kg/m^3

struct Placed {
  std::vector<Vec3> x;
  std::vector<Real> r;
};

// The top face of one cell of [0, 7.5 mm]^3 (normal pointing down into it), fed `mass` at once.
gs::FluxInserter top_face_inserter(gs::InterfaceFace& face, gs::FieldGrid& grid) {
  grid.origin = Vec3::Zero();
  grid.edge = Vec3::Constant(kEdge);
  grid.dims = {1, 1, 1};
  face.axis = 2;
  face.side = 1;
  face.normal = Vec3(0, 0, -1);
  face.centre = Vec3(0.5 * kEdge, 0.5 * kEdge, kEdge);
  face.area = kEdge * kEdge;
  return gs::FluxInserter(face, grid, gs::SizeDistribution::monodisperse(kRadius), kDensity, 0, 1.0,
                          0.0, 42);
}

// A parent bed of spheres twice the grain size on a simple cubic lattice filling the box [lo, hi]
// (one extra layer around it), solid fraction pi / 6.
gs::SphereSet parent_bed(const Vec3& lo, const Vec3& hi) {
  const Real R = 2 * kRadius;
  gs::SphereSet bed;
  for (Real x = lo[0] - R; x < hi[0] + 2 * R; x += 2 * R)
    for (Real y = lo[1] - R; y < hi[1] + 2 * R; y += 2 * R)
      for (Real z = lo[2] - R; z < hi[2] + 2 * R; z += 2 * R) {
        bed.x.emplace_back(x, y, z);
        bed.r.push_back(R);
      }
  return bed;
}

const gs::Domain kOpen(Vec3::Constant(-1), Vec3::Constant(1), {false, false, false});

// Places what `ins` owes with the parent's particles `parent` (default: a bed over the shell)
// and the walls `walls` (default: none).
Placed place_all(gs::FluxInserter& ins, const gs::SphereSet* parent = nullptr,
                 const std::vector<gs::Wall>& walls = {}) {
  Vec3 lo, hi;
  ins.placing_region().bounds(lo, hi);
  gs::OccupancyGrid grid(lo, hi, kRadius, 0.0, gs::SphereSet{}, kOpen);
  const gs::SphereSet bed = parent != nullptr ? *parent : parent_bed(lo, hi);
  const Real reach = ins.face_size();
  const gs::CentreGrid material(lo, hi, reach, 4 * kRadius, bed, kOpen);
  const gs::WallClearance clearance(walls, lo, hi, kRadius), sight_walls(walls, lo, hi, reach);
  const gs::MaterialSight sight{material, sight_walls, reach};
  Placed p;
  ins.place(grid, clearance, kOpen, sight, p.x, p.r);
  return p;
}

// top_face_inserter fed `grains` grains' worth of mass at once, falling at 0.1 m/s.
gs::FluxInserter fed_inserter(gs::InterfaceFace& face, gs::FieldGrid& grid, Real grains) {
  gs::FluxInserter ins = top_face_inserter(face, grid);
  ins.feed(grains * ins.mass_of(kRadius), Vec3(0, 0, -0.1), Vec3::Zero());
  return ins;
}

void test_carries_a_dense_inflow() {
  gs::InterfaceFace face;
  gs::FieldGrid grid;
  gs::FluxInserter ins = fed_inserter(face, grid, 200);
  const Placed p = place_all(ins);
  const Real depth = 4 * kRadius;  // the shell's depth inside the face (cell deeper than 4 r)
  bool straddles = false;
  for (std::size_t i = 0; i < p.x.size(); ++i) {
    const Vec3& x = p.x[i];
    EXPECT(x[0] >= -1e-12 && x[0] <= kEdge + 1e-12 && x[1] >= -1e-12 && x[1] <= kEdge + 1e-12,
           "centre over the face rectangle");
    EXPECT(x[2] <= kEdge + 1e-12 && x[2] >= kEdge - depth + kRadius - 1e-12,
           "centre within the shell's depth");
    straddles = straddles || x[0] < kRadius || x[0] > kEdge - kRadius;
    for (std::size_t j = 0; j < i; ++j)
      EXPECT((x - p.x[j]).norm() >= p.r[i] + p.r[j] - 1e-12, "placed grains do not overlap");
  }
  EXPECT(straddles, "grains straddle the face's edges");
  const Real solid = p.x.size() * (4.0 / 3.0) * M_PI * kRadius * kRadius * kRadius;
  const Real fraction = solid / (kEdge * kEdge * depth);
  std::printf("carries_a_dense_inflow: %zu grains, solid fraction of the shell %.3f\n", p.x.size(),
              fraction);
  EXPECT(fraction >= 0.35, "shell filled to a random packing, got " + std::to_string(fraction) +
                               " (" + std::to_string(p.x.size()) + " grains)");
}

void test_books_stay_exact() {
  gs::InterfaceFace face;
  gs::FieldGrid grid;
  gs::FluxInserter ins = top_face_inserter(face, grid);
  const Real fed = 200.5 * ins.mass_of(kRadius);
  ins.feed(fed, Vec3(0, 0, -0.1), Vec3::Zero());
  place_all(ins);
  EXPECT(ins.inserted_mass() > 0, "something placed");
  EXPECT(std::abs(ins.fed_mass() - ins.inserted_mass() - ins.pending_mass()) <= 1e-12 * fed,
         "fed = inserted + pending");
}

void test_stays_in_the_domain() {
  // A placement region reaching 5 mm past the domain's side x = 0 (a face's band widened past
  // its edges where the face lies on that side).
  const gs::Region region = gs::Region::box(Vec3(-5e-3, 0, 0), Vec3(5e-3, 1e-2, 1e-2));
  const gs::Domain open(Vec3::Constant(-1), Vec3::Constant(1), {false, false, false});
  for (const bool periodic : {false, true}) {
    const gs::Domain domain(Vec3(0, -1, -1), Vec3(1, 1, 1), {periodic, false, false});
    gs::OccupancyGrid grid(Vec3(-5e-3, 0, 0), Vec3(5e-3, 1e-2, 1e-2), kRadius, 0.0, gs::SphereSet{},
                           open);
    std::vector<Real> pending(40, kRadius);
    gs::Rng rng(7);
    Placed p;
    gs::place_pending(pending, region, 50, rng, grid, gs::WallClearance{}, p.x, p.r, &domain);
    int beyond = 0;
    for (const Vec3& x : p.x) beyond += x[0] < 0;
    std::printf("stays_in_the_domain: periodic %d, %zu placed, %d beyond x = 0\n", periodic,
                p.x.size(), beyond);
    EXPECT(p.x.size() >= 10, "grains placed");
    if (periodic)
      EXPECT(beyond > 0, "a periodic side does not stop placement");
    else
      EXPECT(beyond == 0, "no centre beyond a closed side, got " + std::to_string(beyond));
  }
}

void test_goes_where_the_parent_reaches() {
  gs::InterfaceFace face;
  gs::FieldGrid grid;
  gs::FluxInserter ins = fed_inserter(face, grid, 200);
  const Real grain = ins.mass_of(kRadius);
  const gs::SphereSet none;
  const Placed empty = place_all(ins, &none);
  EXPECT(empty.x.empty(),
         "nothing placed without parent particles, got " + std::to_string(empty.x.size()));
  EXPECT(std::abs(ins.pending_mass() - 200 * grain) <= 1e-12 * grain, "what is owed waits");
  // A wall across the shell at x = 3.75 mm (a floor that a face's cell straddles), the parent's
  // bed only on the side x < 3.75 mm.
  const Real split = 0.5 * kEdge;
  gs::Wall wall;
  wall.shape = gs::WallShape::Rectangle;
  wall.point = Vec3(split, -0.01, -0.01);
  wall.edge1 = Vec3(0, 0.03, 0);
  wall.edge2 = Vec3(0, 0, 0.03);
  wall.normal = Vec3(1, 0, 0);
  Vec3 lo, hi;
  ins.placing_region().bounds(lo, hi);
  gs::SphereSet half;
  const gs::SphereSet bed = parent_bed(lo, hi);
  for (std::size_t k = 0; k < bed.x.size(); ++k)
    if (bed.x[k][0] + bed.r[k] <= split) {
      half.x.push_back(bed.x[k]);
      half.r.push_back(bed.r[k]);
    }
  const Placed p = place_all(ins, &half, {wall});
  int beyond = 0;
  for (const Vec3& x : p.x) beyond += x[0] > split;
  std::printf("goes_where_the_parent_reaches: %zu grains placed, %d behind the wall\n", p.x.size(),
              beyond);
  EXPECT(p.x.size() >= 5, "grains placed where the parent is");
  EXPECT(beyond == 0, "no grain behind the wall, got " + std::to_string(beyond));
  // The same without the wall: the parent's reach alone does not stop the other side.
  gs::FluxInserter open_ins = fed_inserter(face, grid, 200);
  const Placed q = place_all(open_ins, &half);
  int across = 0;
  for (const Vec3& x : q.x) across += x[0] > split;
  EXPECT(across > 0, "without the wall grains go to both sides");
}

void test_segments_cross_walls() {
  const Vec3 a(0, 0, 1), b(0, 0, -1), c(0, 0, 0.5);
  gs::Wall plane;  // z = 0, normal up
  EXPECT(gs::segment_crosses(plane, a, b), "a segment through a plane crosses it");
  EXPECT(!gs::segment_crosses(plane, a, c), "one on its side does not");
  gs::Wall rect;
  rect.shape = gs::WallShape::Rectangle;
  rect.point = Vec3(-1, -1, 0);
  rect.edge1 = Vec3(2, 0, 0);
  rect.edge2 = Vec3(0, 2, 0);
  rect.normal = Vec3(0, 0, 1);
  EXPECT(gs::segment_crosses(rect, a, b), "through a rectangle");
  EXPECT(!gs::segment_crosses(rect, a + Vec3(3, 0, 0), b + Vec3(3, 0, 0)), "beside a rectangle");
  gs::Wall cyl;
  cyl.shape = gs::WallShape::Cylinder;
  cyl.point = Vec3(0, 0, 0);
  cyl.axis = Vec3(0, 0, 1);
  cyl.radius = 1;
  cyl.length = 2;
  EXPECT(gs::segment_crosses(cyl, Vec3(0.5, 0, 1), Vec3(1.5, 0, 1)), "out through a mantle");
  EXPECT(!gs::segment_crosses(cyl, Vec3(0.5, 0, 1), Vec3(-0.5, 0.5, 1)), "inside a cylinder");
  EXPECT(!gs::segment_crosses(cyl, Vec3(0.5, 0, 3), Vec3(1.5, 0, 3)), "beyond its open end");
  EXPECT(gs::segment_crosses(cyl, Vec3(-2, 0, 1), Vec3(2, 0, 1)), "across a whole cylinder");
  const Vec3 v0(-1, -1, 0), v1(1, -1, 0), v2(0, 1, 0);
  EXPECT(gs::segment_crosses_triangle(a, b, v0, v1, v2), "through a triangle");
  EXPECT(!gs::segment_crosses_triangle(a, c, v0, v1, v2), "short of a triangle");
  EXPECT(!gs::segment_crosses_triangle(a + Vec3(0, 2, 0), b + Vec3(0, 2, 0), v0, v1, v2),
         "beside a triangle");
}

}  // namespace

int main() {
  test_carries_a_dense_inflow();
  test_books_stay_exact();
  test_stays_in_the_domain();
  test_goes_where_the_parent_reaches();
  test_segments_cross_walls();
  const int failed = test_support::g_failures;
  std::printf("test_flux_inserter: %d checks, %d failed\n", test_support::g_checks, failed);
  return failed == 0 ? 0 : 1;
}
