#include "insert/pack.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <sstream>

#include "core/errors.hpp"

namespace grainscale {

namespace {

// Volume of a sphere, or area of a disc in the 2-D mode.
Real particle_measure(Real r, bool planar) {
  return planar ? M_PI * r * r : (4.0 / 3.0) * M_PI * r * r * r;
}

// Region volume, or the area of the box's x-y cross-section in the 2-D mode.
Real region_measure(const PackSpec& spec) {
  if (!spec.planar) return spec.region.volume();
  Vec3 lo, hi;
  spec.region.bounds(lo, hi);
  return (hi[0] - lo[0]) * (hi[1] - lo[1]);
}

// Near jamming almost every uniform trial position is taken. The sampler then restricts trials to
// voxels of the centres' bounding box that may still hold a free centre for radius rho (the
// smallest radius still to place: space covered for rho is covered for every larger radius).
// A voxel is dropped when no centre in it keeps a sphere of radius rho inside the region, when
// one wall blocks all of it, or when one stored sphere covers it; a trial that fails in a voxel
// splits it into its eight children (down to edge h0 / 2^9), which resolves space covered by
// several spheres together. Voxels are drawn with probability proportional to their volume, then a
// uniform point in it: uniform over the union of the voxels, which holds every free position, so
// rejection keeps the statistics of random sequential addition exact (the scheme of Zhang &
// Torquato, Phys. Rev. E 88, 053312, 2013).
class VoxelSampler {
 public:
  // planar: voxels are squares in the plane z = plane_z (2-D mode).
  VoxelSampler(const Region& region, Real rho, const OccupancyGrid& grid,
               const WallClearance& walls, bool planar, Real plane_z)
      : region_(region), grid_(grid), walls_(walls), rho_(rho), planar_(planar) {
    Vec3 lo, hi;
    region.bounds(lo, hi);
    lo.array() += rho;
    hi.array() -= rho;
    if (planar) lo[2] = hi[2] = plane_z;
    const Vec3 extent = (hi - lo).cwiseMax(Vec3::Constant(1e-300));
    Real h = 0.5 * rho;
    const Real max_voxels = 2e6;  // initial voxels (at most half of kMaxVoxels)
    const int axes = planar ? 2 : 3;
    const Real count = (extent / h).array().head(axes).ceil().prod();
    if (count > max_voxels) h *= std::pow(count / max_voxels, 1.0 / axes) * 1.01;
    int dims[3] = {1, 1, 1};
    for (int a = 0; a < axes; ++a)
      dims[a] = std::max(1, static_cast<int>(std::ceil(extent[a] / h)));
    for (int l = 0; l < kLevels; ++l) edge_[l] = std::ldexp(h, -l);
    for (int z = 0; z < dims[2]; ++z)
      for (int y = 0; y < dims[1]; ++y)
        for (int x = 0; x < dims[0]; ++x) {
          const Vec3 v = lo + h * Vec3(x, y, z);
          if (may_hold_centre(v, 0)) voxels_[0].push_back(v);
        }
    size_ = voxels_[0].size();
  }

  bool empty() const {
    for (const auto& level : voxels_)
      if (!level.empty()) return false;
    return true;
  }

  // A trial centre; (level, slot) name its voxel for refine().
  Vec3 sample(Rng& rng, int& level, std::size_t& slot) const {
    Real total = 0;
    for (int l = 0; l < kLevels; ++l) total += voxels_[l].size() * volume(l);
    Real u = uniform01(rng) * total;
    level = 0;
    while (level + 1 < kLevels &&
           (voxels_[level].empty() || u >= voxels_[level].size() * volume(level))) {
      u -= voxels_[level].size() * volume(level);
      ++level;
    }
    const std::size_t n = voxels_[level].size();
    slot = std::min(static_cast<std::size_t>(uniform01(rng) * n), n - 1);
    const Real u0 = uniform01(rng), u1 = uniform01(rng), u2 = uniform01(rng);
    return voxels_[level][slot] + edge_[level] * Vec3(u0, u1, planar_ ? 0 : u2);
  }

  // After a failed trial: replaces the voxel by those of its children that may hold a centre.
  void refine(int level, std::size_t slot) {
    auto& list = voxels_[level];
    const Vec3 v = list[slot];
    list[slot] = list.back();
    list.pop_back();
    --size_;
    if (!may_hold_centre(v, level)) return;
    if (level + 1 == kLevels || size_ + 8 > kMaxVoxels) {  // finest level or memory bound: keep
      list.push_back(v);
      ++size_;
      return;
    }
    const Real h = edge_[level + 1];
    for (int k = 0; k < (planar_ ? 4 : 8); ++k) {
      const Vec3 c = v + h * Vec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
      if (may_hold_centre(c, level + 1)) {
        voxels_[level + 1].push_back(c);
        ++size_;
      }
    }
  }

 private:
  static constexpr int kLevels = 10;
  static constexpr std::size_t kMaxVoxels = 4'000'000;  // 96 MB of voxel corners
  Real volume(int level) const {
    return planar_ ? edge_[level] * edge_[level] : edge_[level] * edge_[level] * edge_[level];
  }
  bool may_hold_centre(const Vec3& lo, int level) const {
    const Real h = edge_[level];
    const Vec3 diagonal = planar_ ? Vec3(h, h, 0) : Vec3::Constant(h);
    // A free centre p in the voxel is within half a diagonal of the voxel centre c, so the sphere
    // (c, rho - half diagonal) lies inside the region (Mesh too: the sphere (p, rho) is inside,
    // and holds it); no single wall blocks the whole voxel; no single sphere covers it.
    const Real half_diagonal = 0.5 * diagonal.norm();
    const Real inner = rho_ - half_diagonal;
    const Vec3 c = lo + 0.5 * diagonal;
    if (inner >= 0 && !region_.contains(c, inner)) return false;
    if (walls_.blocks(c, half_diagonal, rho_)) return false;
    return !grid_.covers(lo, lo + diagonal, rho_);
  }
  const Region& region_;
  const OccupancyGrid& grid_;
  const WallClearance& walls_;
  Real rho_ = 0;
  bool planar_ = false;
  Real edge_[kLevels] = {};
  std::vector<Vec3> voxels_[kLevels];
  std::size_t size_ = 0;  // voxels in all levels
};

}  // namespace

std::vector<Real> pack_radii(const PackSpec& spec, Rng& rng) {
  std::vector<Real> radii;
  if (spec.count >= 0) {
    if (spec.count > 100'000'000) throw_invalid("Pack.count", "at most 1e8", spec.count);
    radii.reserve(spec.count);
    for (std::int64_t k = 0; k < spec.count; ++k) radii.push_back(spec.radius.sample(rng));
  } else {
    const Real target = spec.volume_fraction * region_measure(spec);
    const Real r_mean = 0.5 * (spec.radius.min_radius() + spec.radius.max_radius());
    if (target / particle_measure(spec.radius.min_radius(), spec.planar) > 1e8 &&
        target / particle_measure(r_mean, spec.planar) > 1e8)
      throw_invalid("Pack.volume_fraction", "a target of at most about 1e8 particles",
                    spec.volume_fraction);
    Real total = 0;
    // Stop at the sample that would take the total further from the target than it is.
    for (;;) {
      const Real r = spec.radius.sample(rng);
      const Real v = particle_measure(r, spec.planar);
      if (total + 0.5 * v > target) break;
      radii.push_back(r);
      total += v;
    }
  }
  std::stable_sort(radii.begin(), radii.end(), std::greater<Real>());
  return radii;
}

Placement place_in_region(const PackSpec& spec, const std::vector<Real>& radii, OccupancyGrid& grid,
                          const WallClearance& walls, Rng& rng) {
  Placement out;
  out.position.reserve(radii.size());
  out.radius.reserve(radii.size());
  Real placed_volume = 0;
  // Plain uniform trials first (cheap while the region is far from full); after `direct` failures
  // for one particle the voxel sampler takes over for the rest of the packing, and max_attempts
  // directed trials decide that a particle finds no room.
  const int direct = 5000;
  std::unique_ptr<VoxelSampler> voxels;
  for (std::size_t k = 0; k < radii.size(); ++k) {
    const Real r = radii[k];
    if (!spec.region.fits(r)) {
      std::ostringstream msg;
      msg << "Pack: a sphere of radius " << shortest(r) << " m does not fit inside the region";
      throw std::runtime_error(msg.str());
    }
    bool ok = false;
    int attempt = 0;
    auto accept = [&](const Vec3& x) {
      grid.add(x, r);
      out.position.push_back(x);
      out.radius.push_back(r);
      placed_volume += particle_measure(r, spec.planar);
      ok = true;
    };
    // A valid centre: sphere inside the region, clear of the walls and of every stored sphere.
    auto free_at = [&](const Vec3& x, bool check_region) {
      return !grid.overlaps(x, r) && (!check_region || spec.region.contains(x, r)) &&
             walls.clear(x, r);
    };
    for (int trial = 0; !voxels && trial < direct && !ok; ++trial) {
      Vec3 x = spec.region.sample(rng, r);
      if (spec.planar) x[2] = spec.plane_z;
      if (free_at(x, !spec.region.samples_inside())) accept(x);
    }
    if (!ok && !voxels)
      voxels = std::make_unique<VoxelSampler>(spec.region,
                                              *std::min_element(radii.begin() + k, radii.end()),
                                              grid, walls, spec.planar, spec.plane_z);
    for (; !ok && !voxels->empty() && attempt < spec.max_attempts; ++attempt) {
      int level = 0;
      std::size_t slot = 0;
      const Vec3 x = voxels->sample(rng, level, slot);
      if (free_at(x, true))
        accept(x);
      else
        voxels->refine(level, slot);
    }
    if (!ok) {
      Real requested = 0;
      for (Real q : radii) requested += particle_measure(q, spec.planar);
      const Real v = region_measure(spec);
      std::ostringstream msg;
      msg.precision(3);
      msg << "Pack placed only " << k << " of " << radii.size() << " particles: particle " << k + 1
          << " (radius " << shortest(r) << " m) found no free position ";
      if (voxels && voxels->empty())
        msg << "(the region is saturated)";
      else
        msg << "in " << spec.max_attempts << " attempts";
      msg << "; the region's volume fraction reached " << placed_volume / v << " of the requested "
          << requested / v
          << ". Nothing was inserted. Random sequential addition jams near 0.38 for equal "
             "spheres (less with particles already inside): lower count/volume_fraction, "
             "enlarge the region, or insert in stages and let the particles settle.";
      throw std::runtime_error(msg.str());
    }
  }
  return out;
}

}  // namespace grainscale
