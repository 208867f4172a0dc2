#include "field/cell_average.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace grainscale {

namespace {

constexpr int kSums = 24;  // mass, volume, count, momentum (3), K (9), W (9)
constexpr int kMass = 0, kVolume = 1, kCount = 2, kMomentum = 3, kKinetic = 6, kVirial = 15;

Vec3 wrapped(const Domain& d, Vec3 x) {
  for (int a = 0; a < 3; ++a) {
    if (!d.periodic[a]) continue;
    const Real len = d.hi[a] - d.lo[a];
    x[a] -= len * std::floor((x[a] - d.lo[a]) / len);
  }
  return x;
}

void add_outer(Real* out, const Vec3& a, const Vec3& b) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out[3 * r + c] += a[r] * b[c];
}

}  // namespace

CellAverager::CellAverager(const FieldGrid& grid, int dimension)
    : grid_(grid),
      dimension_(dimension),
      sums_(static_cast<std::size_t>(grid.n_cells()) * kSums, 0),
      vmin_(3 * static_cast<std::size_t>(grid.n_cells()), std::numeric_limits<Real>::infinity()),
      vmax_(3 * static_cast<std::size_t>(grid.n_cells()), -std::numeric_limits<Real>::infinity()) {}

void CellAverager::sample(const ParticleStore& ps, const ContactStats& stats,
                          const Domain& domain) {
  const Index n = ps.n_owned();
  for (Index i = 0; i < n; ++i) {
    const int c = grid_.cell_of(wrapped(domain, ps.position[i]));
    if (c < 0) continue;
    Real* s = &sums_[static_cast<std::size_t>(c) * kSums];
    const Real m = ps.mass[i], r = ps.radius[i];
    const Vec3& v = ps.velocity[i];
    s[kMass] += m;
    s[kVolume] += dimension_ == 2 ? M_PI * r * r : (4.0 / 3.0) * M_PI * r * r * r;
    s[kCount] += 1;
    for (int a = 0; a < 3; ++a) {
      s[kMomentum + a] += m * v[a];
      vmin_[3 * c + a] = std::min(vmin_[3 * c + a], v[a]);
      vmax_[3 * c + a] = std::max(vmax_[3 * c + a], v[a]);
    }
    add_outer(s + kKinetic, m * v, v);
  }
  for (const ContactRecord& rec : stats.records) {
    const Vec3& xi = ps.position[rec.i];
    const Vec3 point = xi - (ps.radius[rec.i] - 0.5 * rec.overlap) * rec.normal;
    const int ci = grid_.cell_of(wrapped(domain, xi));
    if (ci >= 0)
      add_outer(&sums_[static_cast<std::size_t>(ci) * kSums + kVirial], rec.force, xi - point);
    if (rec.j < 0) continue;
    const Vec3& xj = ps.position[rec.j];
    const int cj = grid_.cell_of(wrapped(domain, xj));
    if (cj >= 0)
      add_outer(&sums_[static_cast<std::size_t>(cj) * kSums + kVirial], -rec.force, xj - point);
  }
  ++samples_;
}

CellFields CellAverager::finish(const Communicator& comm) {
  comm.sum_in_place(sums_);
  // Exact in any order: the component-wise extremes.
  comm.max_in_place(vmax_);
  comm.min_in_place(vmin_);
  const int nc = grid_.n_cells();
  CellFields f;
  f.grid = grid_;
  f.samples = samples_;
  f.mass.assign(nc, 0);
  f.solid_fraction.assign(nc, 0);
  f.particles.assign(nc, 0);
  f.velocity.assign(nc, Vec3::Zero());
  f.stress.assign(nc, {});
  f.velocity_min.assign(nc, Vec3::Zero());
  f.velocity_max.assign(nc, Vec3::Zero());
  f.velocity_spread.assign(nc, Vec3::Zero());
  const Real volume = grid_.cell_volume();
  const Real per_sample = samples_ > 0 ? 1.0 / samples_ : 0;
  for (int c = 0; c < nc; ++c) {
    const Real* s = &sums_[static_cast<std::size_t>(c) * kSums];
    const Real m = s[kMass] * per_sample;
    f.mass[c] = m;
    f.solid_fraction[c] = s[kVolume] * per_sample / volume;
    f.particles[c] = s[kCount] * per_sample;
    const Vec3 p(s[kMomentum], s[kMomentum + 1], s[kMomentum + 2]);
    if (m > 0) f.velocity[c] = p * per_sample / m;
    for (int k = 0; k < 9; ++k) {
      const int r = k / 3, col = k % 3;
      Real kinetic = s[kKinetic + k] * per_sample;
      if (m > 0) kinetic -= p[r] * per_sample * p[col] * per_sample / m;
      f.stress[c][k] = (kinetic + s[kVirial + k] * per_sample) / volume;
      if (r == col && m > 0) f.velocity_spread[c][r] = std::sqrt(std::max(kinetic / m, Real(0)));
    }
    if (s[kCount] > 0)
      for (int a = 0; a < 3; ++a) {
        f.velocity_min[c][a] = vmin_[3 * c + a];
        f.velocity_max[c][a] = vmax_[3 * c + a];
      }
  }
  std::fill(sums_.begin(), sums_.end(), 0);
  std::fill(vmin_.begin(), vmin_.end(), std::numeric_limits<Real>::infinity());
  std::fill(vmax_.begin(), vmax_.end(), -std::numeric_limits<Real>::infinity());
  samples_ = 0;
  return f;
}

}  // namespace grainscale
