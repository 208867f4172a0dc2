// The stress condition's push at a hierarchy's interface faces (prints every failed check, returns
// non-zero if any failed):
//   totals_pressure_times_area – a layer of grains under the top faces of a 30 mm box, dense or
//                                with half the grains, feels a total push of p x the faces' area
//                                (each grain's p pi r^2 is scaled by p A / sum p pi r^2), so the
//                                traction does not depend on the layer's packing; a layer so
//                                sparse that the scale reaches its bound feels less.
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "coupling/coupling_forces.hpp"
#include "expect.hpp"
#include "field/exchange_grid.hpp"
#include "insert/region.hpp"
#include "state/domain.hpp"
#include "state/particle_store.hpp"

namespace gs = grainscale;
using gs::Real;
using gs::Vec3;

namespace {

constexpr Real kBox = 0.03;      // m, the region [0, 30 mm]^3
constexpr Real kRadius = 1e-3;   // m
constexpr Real kPressure = 300;  // Pa on every top face

// Total vertical push on a layer of grains 1.2 mm under the top face, every `step_x`-th and
// `step_y`-th site of a 15 x 15 lattice of pitch 2 mm.
Real total_push(int step_x, int step_y) {
  const gs::Domain domain(Vec3::Constant(-0.1), Vec3::Constant(0.1), {false, false, false});
  auto grid = std::make_shared<const gs::ExchangeGrid>(
      gs::Region::box(Vec3::Zero(), Vec3::Constant(kBox)), 0.0075, domain, "test");
  gs::CouplingForces forces(grid, 2.6e-3, 0.5e-3);
  const auto& faces = grid->faces();
  forces.pressure.assign(faces.size(), 0.0);
  forces.max_inward_speed.assign(faces.size(), 1.0);
  for (std::size_t f = 0; f < faces.size(); ++f)
    if (faces[f].normal[2] < -0.5) forces.pressure[f] = kPressure;
  gs::ParticleStore ps;
  gs::GlobalId id = 0;
  for (int i = 0; i < 15; i += step_x)
    for (int j = 0; j < 15; j += step_y)
      ps.add_owned(id++, Vec3(1e-3 + 2e-3 * i, 1e-3 + 2e-3 * j, kBox - 1.2e-3), Vec3::Zero(),
                   Vec3::Zero(), kRadius, 1e-5, 1e-12, 0);
  for (gs::Index i = 0; i < ps.n_local(); ++i) ps.force[i].setZero();
  forces.locate(ps, domain);
  const std::vector<Real> scale = forces.push_scale(forces.push_total());
  forces.apply(ps, 1e-6, scale);
  Real fz = 0;
  for (gs::Index i = 0; i < ps.n_owned(); ++i) fz += ps.force[i][2];
  return fz;
}

void test_totals_pressure_times_area() {
  const Real expected = -kPressure * kBox * kBox;  // N, downwards
  for (const auto& [sx, sy] : {std::pair{1, 1}, std::pair{2, 1}}) {
    const Real fz = total_push(sx, sy);
    std::printf("totals_pressure_times_area: every (%d, %d) site, F_z = %.6g N, p A = %.6g N\n", sx,
                sy, fz, expected);
    EXPECT(std::abs(fz - expected) <= 1e-12 * std::abs(expected),
           "total push p A, got " + std::to_string(fz));
  }
  // Every 4th site both ways: one grain per face, whose scale (p A / p pi r^2 = 17.9) is held at
  // its bound.
  const Real sparse = total_push(4, 4);
  const Real bounded =
      16 * gs::CouplingForces::kMaxPushScale * kPressure * M_PI * kRadius * kRadius;
  EXPECT(std::abs(sparse + bounded) <= 1e-12 * bounded,
         "a sparse layer's push held at the bound, got " + std::to_string(sparse));
}

}  // namespace

int main() {
  test_totals_pressure_times_area();
  const int failed = test_support::g_failures;
  std::printf("test_coupling_forces: %d checks, %d failed\n", test_support::g_checks, failed);
  return failed == 0 ? 0 : 1;
}
