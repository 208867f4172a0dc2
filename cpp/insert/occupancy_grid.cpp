#include "insert/occupancy_grid.hpp"

#include <algorithm>
#include <cmath>

#include "state/periodic_images.hpp"

namespace grainscale {

namespace {

bool touches(const Vec3& p, Real r, const Vec3& box_lo, const Vec3& box_hi) {
  return ((p.array() + r) >= box_lo.array()).all() && ((p.array() - r) <= box_hi.array()).all();
}

}  // namespace

void OccupancyGrid::collect_nearby(const Vec3& lo, const Vec3& hi, Real max_new_radius, Real r_old,
                                   const ParticleStore& ps, const Domain& domain, SphereSet& out) {
  const Vec3 grow = Vec3::Constant(max_new_radius + r_old);
  const Vec3 box_lo = lo - grow, box_hi = hi + grow;
  for (Index i = 0; i < ps.n_owned(); ++i) {
    bool near = false;
    for_images(ps.position[i], domain,
               [&](const Vec3& p) { near = near || touches(p, ps.radius[i], box_lo, box_hi); });
    if (!near) continue;
    out.x.push_back(ps.position[i]);
    out.r.push_back(ps.radius[i]);
  }
}

OccupancyGrid::OccupancyGrid(const Vec3& lo, const Vec3& hi, Real max_new_radius, Real r_old,
                             const SphereSet& present, const Domain& domain) {
  // Existing spheres matter if they reach within their radius of the box grown by the largest
  // new radius.
  const Vec3 grow = Vec3::Constant(max_new_radius + r_old);
  const Vec3 box_lo = lo - grow, box_hi = hi + grow;
  for (std::size_t i = 0; i < present.x.size(); ++i) {
    const Real r = present.r[i];
    for_images(present.x[i], domain, [&](const Vec3& p) {
      if (touches(p, r, box_lo, box_hi)) {
        x_.push_back(p);
        r_.push_back(r);
      }
    });
  }
  Real r_max = max_new_radius;
  for (Real r : r_) r_max = std::max(r_max, r);
  Real cell = std::max(max_new_radius + r_max, Real(1e-300));
  const Vec3 extent = (hi - lo).cwiseMax(Vec3::Constant(cell));
  // At most ~4 million cells: a sparse set of large particles gets larger cells instead.
  const Real max_cells = 4.0e6;
  const Real cells = (extent / cell).array().ceil().prod();
  if (cells > max_cells) cell *= std::cbrt(cells / max_cells) * 1.01;
  lo_ = lo;
  inv_cell_ = 1 / cell;
  for (int a = 0; a < 3; ++a)
    dims_[a] = std::max(1, static_cast<int>(std::ceil(extent[a] * inv_cell_)));
  head_.assign(static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2], -1);
  next_.assign(x_.size(), -1);
  for (std::size_t k = 0; k < x_.size(); ++k) {
    const int c = cell_of(x_[k]);
    next_[k] = head_[c];
    head_[c] = static_cast<int>(k);
  }
}

int OccupancyGrid::cell_of(const Vec3& x) const {
  int c[3];
  for (int a = 0; a < 3; ++a) {
    const Real f = std::floor((x[a] - lo_[a]) * inv_cell_);
    c[a] = static_cast<int>(std::clamp<Real>(f, 0, dims_[a] - 1));
  }
  return c[0] + dims_[0] * (c[1] + dims_[1] * c[2]);
}

void OccupancyGrid::add(const Vec3& x, Real r) {
  const int c = cell_of(x);
  x_.push_back(x);
  r_.push_back(r);
  next_.push_back(head_[c]);
  head_[c] = static_cast<int>(x_.size()) - 1;
}

bool OccupancyGrid::overlaps(const Vec3& x, Real r) const {
  const int c = cell_of(x);
  const int cx = c % dims_[0], cy = (c / dims_[0]) % dims_[1], cz = c / (dims_[0] * dims_[1]);
  for (int z = std::max(cz - 1, 0); z <= std::min(cz + 1, dims_[2] - 1); ++z)
    for (int y = std::max(cy - 1, 0); y <= std::min(cy + 1, dims_[1] - 1); ++y)
      for (int xx = std::max(cx - 1, 0); xx <= std::min(cx + 1, dims_[0] - 1); ++xx)
        for (int k = head_[xx + dims_[0] * (y + dims_[1] * z)]; k >= 0; k = next_[k]) {
          const Real s = r + r_[k];
          if ((x_[k] - x).squaredNorm() < s * s) return true;
        }
  return false;
}

bool OccupancyGrid::covers(const Vec3& lo, const Vec3& hi, Real r) const {
  // A covering sphere j has every point of the box closer than r + r_j <= cell size, hence its
  // centre lies in the 27-cell stencil of the box centre.
  const int c = cell_of(0.5 * (lo + hi));
  const int cx = c % dims_[0], cy = (c / dims_[0]) % dims_[1], cz = c / (dims_[0] * dims_[1]);
  for (int z = std::max(cz - 1, 0); z <= std::min(cz + 1, dims_[2] - 1); ++z)
    for (int y = std::max(cy - 1, 0); y <= std::min(cy + 1, dims_[1] - 1); ++y)
      for (int xx = std::max(cx - 1, 0); xx <= std::min(cx + 1, dims_[0] - 1); ++xx)
        for (int k = head_[xx + dims_[0] * (y + dims_[1] * z)]; k >= 0; k = next_[k]) {
          // Farthest point of the box from the centre: a corner.
          const Vec3 far = (x_[k] - lo).cwiseAbs().cwiseMax((x_[k] - hi).cwiseAbs());
          const Real s = r + r_[k];
          if (far.squaredNorm() < s * s) return true;
        }
  return false;
}

}  // namespace grainscale
