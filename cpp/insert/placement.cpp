#include "insert/placement.hpp"

namespace grainscale {

void place_pending(std::vector<Real>& pending, const Region& region, int max_attempts, Rng& rng,
                   OccupancyGrid& grid, const WallClearance& walls, std::vector<Vec3>& position,
                   std::vector<Real>& radius, const Domain* domain, const MaterialSight* sight,
                   int give_up_after) {
  const auto in_domain = [domain](const Vec3& x) {
    if (domain == nullptr) return true;
    for (int a = 0; a < 3; ++a)
      if (!domain->periodic[a] && !domain->inside(x, a)) return false;
    return true;
  };
  const auto in_sight = [sight](const Vec3& x) {
    if (sight == nullptr) return true;
    Vec3 from;
    return sight->material.nearest(x, sight->reach, from) && !sight->walls.separates(x, from);
  };
  int failures = 0;
  std::size_t k = 0;
  std::vector<Real> still_pending;
  for (; k < pending.size() && failures < give_up_after; ++k) {
    const Real r = pending[k];
    bool ok = false;
    for (int attempt = 0; attempt < max_attempts && !ok; ++attempt) {
      const Vec3 x = region.sample(rng, r);
      if ((region.samples_inside() || region.contains(x, r)) && in_domain(x) &&
          !grid.overlaps(x, r) && walls.clear(x, r) && in_sight(x)) {
        grid.add(x, r);
        position.push_back(x);
        radius.push_back(r);
        ok = true;
      }
    }
    if (ok) {
      failures = 0;
    } else {
      ++failures;
      still_pending.push_back(r);
    }
  }
  still_pending.insert(still_pending.end(), pending.begin() + k, pending.end());
  pending.swap(still_pending);
}

void write_pending(std::ostream& out, const std::vector<Real>& pending, const Rng& rng) {
  out << ' ' << pending.size();
  for (Real r : pending) out << ' ' << r;
  out << ' ' << rng;
}

void read_pending(std::istream& in, std::vector<Real>& pending, Rng& rng) {
  std::size_t n = 0;
  in >> n;
  pending.assign(in ? n : 0, 0);
  for (Real& r : pending) in >> r;
  in >> rng;
}

}  // namespace grainscale
