#include "coupling/face_flux.hpp"

#include <cmath>
#include <cstring>
#include <unordered_set>

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

constexpr int kWidth = 10;  // mass, count, momentum (3), spin (3), inertia, padding

void add_row(std::vector<Real>& sums, int face, Real m, const Vec3& v, Real inertia,
             const Vec3& w) {
  Real* s = &sums[static_cast<std::size_t>(face) * kWidth];
  s[0] += m;
  s[1] += 1;
  for (int a = 0; a < 3; ++a) {
    s[2 + a] += m * v[a];
    s[5 + a] += inertia * w[a];
  }
  s[8] += inertia;
}

FaceFlux row(const std::vector<Real>& sums, std::size_t face) {
  const Real* s = &sums[face * kWidth];
  FaceFlux f;
  f.mass = s[0];
  f.count = s[1];
  f.momentum = Vec3(s[2], s[3], s[4]);
  f.spin = Vec3(s[5], s[6], s[7]);
  f.inertia = s[8];
  return f;
}

}  // namespace

void FaceFluxMeter::start(const ParticleStore& ps, const ExchangeGrid& grid, const Domain& domain,
                          Real margin, const Communicator& comm) {
  const FieldGrid& g = grid.grid();
  const Vec3 centre = 0.5 * (g.origin + g.upper());
  std::vector<Real> mine;  // id (bits), x, y, z, mass, inside
  for (Index i = 0; i < ps.n_owned(); ++i) {
    const Vec3 x = nearest_image(ps.position[i], centre, domain);
    if (!near_grid(x, g, margin)) continue;
    mine.insert(mine.end(),
                {id_bits(ps.id[i]), x[0], x[1], x[2], ps.mass[i], grid.contains(x) ? 1.0 : 0.0});
  }
  const std::vector<Real> values = comm.allgather(mine);
  start_.clear();
  index_.clear();
  for (std::size_t k = 0; k + 5 < values.size(); k += 6) {
    const GlobalId id = bits_id(values[k]);
    index_[id] = start_.size();
    start_.push_back(
        {id, Vec3(values[k + 1], values[k + 2], values[k + 3]), values[k + 4], values[k + 5] > 0});
  }
}

IntervalFlux FaceFluxMeter::finish(const ParticleStore& ps, const ExchangeGrid& grid,
                                   const Domain& domain, const std::vector<GlobalId>& lost,
                                   const Communicator& comm) {
  const std::size_t nf = grid.faces().size(), ns = start_.size();
  const Vec3 centre = 0.5 * (grid.grid().origin + grid.grid().upper());
  // Layout: inward rows, outward rows, then per start entry whether it still exists, then the
  // mass inside now.
  std::vector<Real> sums(2 * nf * kWidth + ns + 1, 0);
  Real* present = &sums[2 * nf * kWidth];
  std::vector<Real> outward_rows(nf * kWidth, 0);
  for (Index i = 0; i < ps.n_owned(); ++i) {
    const auto it = index_.find(ps.id[i]);
    const Vec3 x =
        nearest_image(ps.position[i], it == index_.end() ? centre : start_[it->second].x, domain);
    const bool inside = grid.contains(x);
    if (inside) present[ns] += ps.mass[i];
    if (it == index_.end() && !inside) continue;
    const Real m = ps.mass[i], inertia = 1 / ps.inv_inertia[i];
    if (it == index_.end()) {  // born inside during the interval
      const int f = grid.nearest_face(x);
      if (f >= 0) add_row(sums, f, m, ps.velocity[i], inertia, ps.angular_velocity[i]);
      continue;
    }
    present[it->second] = 1;
    const Start& s = start_[it->second];
    if (inside == s.inside) continue;
    if (inside) {
      const int f = grid.entry_face(s.x, x);
      if (f >= 0) add_row(sums, f, m, ps.velocity[i], inertia, ps.angular_velocity[i]);
    } else {
      // The face a straight path from now back to the start enters through: the exit face.
      int f = grid.entry_face(x, s.x);
      if (f < 0) f = grid.nearest_face(x);
      if (f >= 0) add_row(outward_rows, f, m, ps.velocity[i], inertia, ps.angular_velocity[i]);
    }
  }
  std::copy(outward_rows.begin(), outward_rows.end(), sums.begin() + nf * kWidth);
  comm.sum_in_place(sums);
  IntervalFlux out;
  out.inward.resize(nf);
  out.outward.resize(nf);
  for (std::size_t f = 0; f < nf; ++f) {
    out.inward[f] = row(sums, f);
    out.outward[f] = row(sums, nf + f);
  }
  std::vector<Real> mine_lost;
  for (GlobalId id : lost) mine_lost.push_back(id_bits(id));
  std::unordered_set<GlobalId> lost_ids;
  for (Real r : comm.allgather(mine_lost)) lost_ids.insert(bits_id(r));
  for (std::size_t k = 0; k < ns; ++k)
    if (start_[k].inside && present[k] == 0) {
      out.vanished_mass += start_[k].mass;
      out.vanished_count += 1;
      if (lost_ids.count(start_[k].id)) out.vanished_lost_mass += start_[k].mass;
    }
  out.inside_mass = present[ns];
  start_.clear();
  index_.clear();
  return out;
}

}  // namespace grainscale
