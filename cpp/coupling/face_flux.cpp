#include "coupling/face_flux.hpp"

#include <cmath>
#include <cstring>

namespace grainscale {

namespace {

// x mapped to the periodic image nearest to `near` (positions drift out of the box between
// rebuilds and wrap at them).
Vec3 nearest_image(Vec3 x, const Vec3& near, const Domain& d) {
  for (int a = 0; a < 3; ++a) {
    if (!d.periodic[a]) continue;
    const Real len = d.hi[a] - d.lo[a];
    x[a] -= len * std::round((x[a] - near[a]) / len);
  }
  return x;
}

bool near_grid(const Vec3& x, const FieldGrid& g, Real margin) {
  const Vec3 lo = g.origin, hi = g.upper();
  for (int a = 0; a < 3; ++a)
    if (x[a] < lo[a] - margin || x[a] > hi[a] + margin) return false;
  return true;
}

}  // namespace

void FaceFluxMeter::start(const ParticleStore& ps, const ExchangeGrid& grid, const Domain& domain,
                          Real margin, const Communicator& comm) {
  const FieldGrid& g = grid.grid();
  const Vec3 centre = 0.5 * (g.origin + g.upper());
  std::vector<Real> mine;  // id (bits), x, y, z
  for (Index i = 0; i < ps.n_owned(); ++i) {
    const Vec3 x = nearest_image(ps.position[i], centre, domain);
    if (!near_grid(x, g, margin) || grid.contains(x)) continue;
    Real id;
    std::memcpy(&id, &ps.id[i], sizeof id);
    mine.insert(mine.end(), {id, x[0], x[1], x[2]});
  }
  std::vector<char> bytes(mine.size() * sizeof(Real));
  if (!bytes.empty()) std::memcpy(bytes.data(), mine.data(), bytes.size());
  const std::vector<char> all = comm.allgather(bytes, nullptr);
  std::vector<Real> values(all.size() / sizeof(Real));
  if (!values.empty()) std::memcpy(values.data(), all.data(), all.size());
  start_.clear();
  for (std::size_t k = 0; k + 3 < values.size(); k += 4) {
    GlobalId id;
    std::memcpy(&id, &values[k], sizeof id);
    start_[id] = Vec3(values[k + 1], values[k + 2], values[k + 3]);
  }
}

std::vector<FaceFlux> FaceFluxMeter::finish(const ParticleStore& ps, const ExchangeGrid& grid,
                                            const Domain& domain, const Communicator& comm) {
  const std::size_t nf = grid.faces().size();
  constexpr int kWidth = 12;  // mass, count, momentum (3), spin (3), inertia, padding
  std::vector<Real> sums(nf * kWidth, 0);
  for (Index i = 0; i < ps.n_owned(); ++i) {
    const auto it = start_.find(ps.id[i]);
    if (it == start_.end()) continue;
    const Vec3 x = nearest_image(ps.position[i], it->second, domain);
    if (!grid.contains(x)) continue;
    const int f = grid.entry_face(it->second, x);
    if (f < 0) continue;
    const Real m = ps.mass[i], inertia = 1 / ps.inv_inertia[i];
    Real* s = &sums[static_cast<std::size_t>(f) * kWidth];
    s[0] += m;
    s[1] += 1;
    for (int a = 0; a < 3; ++a) {
      s[2 + a] += m * ps.velocity[i][a];
      s[5 + a] += inertia * ps.angular_velocity[i][a];
    }
    s[8] += inertia;
  }
  comm.sum_in_place(sums);
  std::vector<FaceFlux> out(nf);
  for (std::size_t f = 0; f < nf; ++f) {
    const Real* s = &sums[f * kWidth];
    out[f].mass = s[0];
    out[f].count = s[1];
    out[f].momentum = Vec3(s[2], s[3], s[4]);
    out[f].spin = Vec3(s[5], s[6], s[7]);
    out[f].inertia = s[8];
  }
  start_.clear();
  return out;
}

}  // namespace grainscale
