#include "coupling/coupling_forces.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"

namespace grainscale {

CouplingForces::CouplingForces(std::shared_ptr<const ExchangeGrid> grid, Real layer, Real fade)
    : grid_(std::move(grid)), layer_(layer), fade_(fade) {
  if (!(layer > 0) || !std::isfinite(layer))
    throw_invalid("Exchange.layer", "positive and finite (m)", layer);
  if (!(fade > 0) || !(fade <= layer))
    throw_invalid("Exchange.fade", "positive and at most the layer thickness (m)", fade);
}

void CouplingForces::locate(const ParticleStore& ps, const Domain& domain) const {
  inside_.clear();
  pushes_.clear();
  const FieldGrid& g = grid_->grid();
  const bool pushing = !pressure.empty();
  const Vec3 lo = g.origin, hi = g.upper();
  for (Index i = 0; i < ps.n_owned(); ++i) {
    Vec3 x = ps.position[i];
    for (int a = 0; a < 3; ++a)
      if (domain.periodic[a]) {
        const Real len = domain.hi[a] - domain.lo[a];
        x[a] -= len * std::floor((x[a] - domain.lo[a]) / len);
      }
    if (x[0] < lo[0] || x[1] < lo[1] || x[2] < lo[2] || x[0] > hi[0] || x[1] > hi[1] ||
        x[2] > hi[2])
      continue;  // most particles of a coarse level: far from the fine region
    const int c = g.cell_of(x);
    if (c < 0) continue;
    inside_.emplace_back(i, c);
    if (!pushing || !grid_->boundary(c)) continue;
    const Real r = ps.radius[i];
    for (int f : grid_->faces_of(c)) {
      const InterfaceFace& face = grid_->faces()[f];
      const Real p = pressure[f];
      if (!(p > 0)) continue;
      const Real s = (x[face.axis] - face.centre[face.axis]) * face.normal[face.axis];
      if (s < 0 || s >= layer_) continue;
      if (ps.velocity[i].dot(face.normal) > max_inward_speed[f]) continue;
      Real w = 1;
      if (s > layer_ - fade_) {
        const Real q = std::sin(0.5 * M_PI * (layer_ - s) / fade_);
        w = q * q;
      }
      pushes_.push_back({i, f, p * M_PI * r * r * w, s});
    }
  }
}

std::vector<Real> CouplingForces::push_total() const {
  std::vector<Real> total(grid_->faces().size(), 0.0);
  for (const Push& p : pushes_) total[p.face] += p.magnitude;
  return total;
}

std::vector<Real> CouplingForces::push_scale(const std::vector<Real>& total) const {
  const auto& faces = grid_->faces();
  std::vector<Real> scale(faces.size(), 1.0);
  for (std::size_t f = 0; f < faces.size(); ++f)
    if (total[f] > 0) scale[f] = std::min(pressure[f] * faces[f].area / total[f], kMaxPushScale);
  return scale;
}

void CouplingForces::apply(ParticleStore& ps, Real dt, const std::vector<Real>& scale) const {
  const bool limited = !velocity_min.empty();
  if (!acceleration.empty())
    for (const auto& [i, c] : inside_) {
      Vec3 a = acceleration[c];
      if (limited)
        for (int k = 0; k < 3; ++k) {
          if (a[k] == 0) continue;
          const Real room = a[k] > 0 ? velocity_max[c][k] - ps.velocity[i][k]
                                     : velocity_min[c][k] - ps.velocity[i][k];
          a[k] *= std::clamp(room / (a[k] * dt), Real(0), Real(1));
        }
      ps.force[i] += ps.mass[i] * a;
    }
  const auto& faces = grid_->faces();
  for (const Push& p : pushes_)
    ps.force[p.particle] += scale[p.face] * p.magnitude * faces[p.face].normal;
}

std::vector<Real> CouplingForces::push_moment(const std::vector<Real>& scale) const {
  std::vector<Real> moment(grid_->faces().size(), 0.0);
  for (const Push& p : pushes_) moment[p.face] += scale[p.face] * p.magnitude * p.depth;
  return moment;
}

}  // namespace grainscale
