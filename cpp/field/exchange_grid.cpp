#include "field/exchange_grid.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"

namespace grainscale {

ExchangeGrid::ExchangeGrid(const Region& region, Real cell_size, const Domain& domain,
                           const std::string& what) {
  if (!(cell_size > 0) || !std::isfinite(cell_size))
    throw_invalid(what + ".cell_size", "positive and finite (m)", cell_size);
  Vec3 lo, hi;
  region.bounds(lo, hi);
  for (int a = 0; a < 3; ++a) {
    const Real len = hi[a] - lo[a];
    grid_.dims[a] = std::max(1, static_cast<int>(std::lround(len / cell_size)));
    grid_.edge[a] = len / grid_.dims[a];
  }
  grid_.origin = lo;
  const int nc = grid_.n_cells();
  inside_.assign(nc, 0);
  boundary_.assign(nc, 0);
  faces_of_.assign(nc, {});
  for (int c = 0; c < nc; ++c) {
    inside_[c] = region.contains(grid_.centre(c));
    region_cells_ += inside_[c];
  }
  if (region_cells_ == 0)
    throw_invalid(what + ".cell_size", "small enough that some cell centre lies in the region",
                  cell_size);
  for (int c = 0; c < nc; ++c) {
    if (!inside_[c]) continue;
    const auto k = grid_.coords(c);
    for (int a = 0; a < 3; ++a)
      for (int side : {-1, +1}) {
        auto n = k;
        n[a] += side;
        const bool outside_grid = n[a] < 0 || n[a] >= grid_.dims[a];
        if (!outside_grid && inside_[grid_.index(n[0], n[1], n[2])]) continue;
        InterfaceFace f;
        f.cell = c;
        f.axis = a;
        f.side = side;
        f.centre = grid_.centre(c);
        f.centre[a] += 0.5 * side * grid_.edge[a];
        f.normal = Vec3::Zero();
        f.normal[a] = -side;
        f.area = grid_.cell_volume() / grid_.edge[a];
        // A face on a closed side of the box is a wall of the simulation, not an interface.
        const Real tol = 1e-9 * (domain.hi[a] - domain.lo[a]);
        if (!domain.periodic[a] &&
            (f.centre[a] <= domain.lo[a] + tol || f.centre[a] >= domain.hi[a] - tol))
          continue;
        faces_of_[c].push_back(static_cast<int>(faces_.size()));
        faces_.push_back(f);
        boundary_[c] = 1;
      }
    interior_cells_ += !boundary_[c];
  }
  if (interior_cells_ == 0)
    throw_invalid(what + ".cell_size",
                  "small enough that the region has interior cells (region cells with no "
                  "interface face: at least 3 cells across the region between its faces)",
                  cell_size);
}

bool ExchangeGrid::near_region(const Vec3& x, Real band) const {
  const int c = grid_.cell_of(x);
  if (inside(c)) return true;
  // The region cells around x: those whose box lies within `band` of it.
  const Vec3 lo = grid_.origin;
  int k0[3], k1[3];
  for (int a = 0; a < 3; ++a) {
    k0[a] = std::max(0, static_cast<int>(std::floor((x[a] - band - lo[a]) / grid_.edge[a])));
    k1[a] = std::min(grid_.dims[a] - 1,
                     static_cast<int>(std::floor((x[a] + band - lo[a]) / grid_.edge[a])));
    if (k0[a] > k1[a]) return false;
  }
  for (int i = k0[0]; i <= k1[0]; ++i)
    for (int j = k0[1]; j <= k1[1]; ++j)
      for (int k = k0[2]; k <= k1[2]; ++k) {
        const int n = grid_.index(i, j, k);
        if (!inside_[n]) continue;
        const Vec3 cell_lo = lo + Vec3(i * grid_.edge[0], j * grid_.edge[1], k * grid_.edge[2]);
        const Vec3 gap = (cell_lo - x).cwiseMax(x - cell_lo - grid_.edge).cwiseMax(0.0);
        if (gap.squaredNorm() <= band * band) return true;
      }
  return false;
}

int ExchangeGrid::nearest_face(const Vec3& x) const {
  int best = -1;
  Real best_d2 = INFINITY;
  for (std::size_t f = 0; f < faces_.size(); ++f) {
    const InterfaceFace& face = faces_[f];
    Vec3 gap = Vec3::Zero();
    for (int a = 0; a < 3; ++a) {
      const Real d = x[a] - face.centre[a];
      gap[a] = a == face.axis ? d : std::max(std::abs(d) - 0.5 * grid_.edge[a], Real(0));
    }
    if (gap.squaredNorm() < best_d2) {
      best_d2 = gap.squaredNorm();
      best = static_cast<int>(f);
    }
  }
  return best;
}

int ExchangeGrid::entry_face(const Vec3& from, const Vec3& to) const {
  const Vec3 d = to - from;
  const Vec3 lo = grid_.origin, hi = grid_.upper();
  // Clip the segment to the grid's box (slab method); remember the face it enters through.
  Real t0 = 0, t1 = 1;
  int entry_axis = -1, entry_side = 0;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0) {
      if (from[a] < lo[a] || from[a] > hi[a]) return -1;
      continue;
    }
    Real ta = (lo[a] - from[a]) / d[a], tb = (hi[a] - from[a]) / d[a];
    int side = -1;  // moving up, the box is entered through a cell's lower face
    if (ta > tb) {
      std::swap(ta, tb);
      side = +1;
    }
    if (ta > t0) {
      t0 = ta;
      entry_axis = a;
      entry_side = side;
    }
    t1 = std::min(t1, tb);
  }
  if (t0 > t1) return -1;
  int k[3], step[3];
  Real t_next[3], t_delta[3];
  const Vec3 p = from + t0 * d;
  for (int a = 0; a < 3; ++a) {
    k[a] = std::clamp(static_cast<int>(std::floor((p[a] - lo[a]) / grid_.edge[a])), 0,
                      grid_.dims[a] - 1);
    step[a] = d[a] > 0 ? 1 : (d[a] < 0 ? -1 : 0);
    if (step[a] == 0) {
      t_next[a] = t_delta[a] = INFINITY;
      continue;
    }
    const Real boundary = lo[a] + (k[a] + (step[a] > 0 ? 1 : 0)) * grid_.edge[a];
    t_next[a] = (boundary - from[a]) / d[a];
    t_delta[a] = grid_.edge[a] / std::abs(d[a]);
  }
  auto face = [&](int cell, int axis, int side) {
    for (int f : faces_of_[cell])
      if (faces_[f].axis == axis && faces_[f].side == side) return f;
    return -1;
  };
  // Walk the cells along the segment (Amanatides & Woo 1987); a start outside the grid's box
  // counts as outside the region.
  bool was_inside = entry_axis < 0 ? inside(grid_.index(k[0], k[1], k[2])) : false;
  int last_axis = entry_axis, last_side = entry_side;
  for (;;) {
    const int c = grid_.index(k[0], k[1], k[2]);
    if (inside_[c] && !was_inside && last_axis >= 0) return face(c, last_axis, last_side);
    was_inside = inside_[c];
    int a = 0;
    if (t_next[1] < t_next[a]) a = 1;
    if (t_next[2] < t_next[a]) a = 2;
    if (!(t_next[a] <= t1)) return -1;
    k[a] += step[a];
    if (k[a] < 0 || k[a] >= grid_.dims[a]) return -1;
    t_next[a] += t_delta[a];
    last_axis = a;
    last_side = step[a] > 0 ? -1 : +1;
  }
}

}  // namespace grainscale
