#include "parallel/ghost_exchange.hpp"

#include <cmath>

namespace grainscale {

void wrap_periodic(ParticleStore& ps, const Domain& domain) {
  const Vec3 L = domain.length();
  for (int a = 0; a < 3; ++a) {
    if (!domain.periodic[a]) continue;
    for (Index i = 0; i < ps.n_owned(); ++i) {
      Real& x = ps.position[i][a];
      if (x < domain.lo[a] || x >= domain.hi[a]) {
        x -= L[a] * std::floor((x - domain.lo[a]) / L[a]);
        if (x >= domain.hi[a]) x = domain.lo[a];  // round-off at the upper face
      }
    }
  }
}

void GhostExchange::build(ParticleStore& ps, const Domain& domain, Real cutoff) const {
  ps.clear_ghosts();
  const Vec3 L = domain.length();
  const Index n = ps.n_owned();
  for (Index i = 0; i < n; ++i) {
    // Per axis: which images are needed (-1: shifted down by L, +1: shifted up by L).
    int lo_img[3], hi_img[3];
    for (int a = 0; a < 3; ++a) {
      lo_img[a] = hi_img[a] = 0;
      if (!domain.periodic[a]) continue;
      const Real x = ps.position[i][a];
      if (x < domain.lo[a] + cutoff) hi_img[a] = 1;
      if (x > domain.hi[a] - cutoff) lo_img[a] = -1;
    }
    for (int sz = lo_img[2]; sz <= hi_img[2]; ++sz)
      for (int sy = lo_img[1]; sy <= hi_img[1]; ++sy)
        for (int sx = lo_img[0]; sx <= hi_img[0]; ++sx) {
          if (sx == 0 && sy == 0 && sz == 0) continue;
          ps.add_ghost(i, Vec3(sx * L[0], sy * L[1], sz * L[2]));
        }
  }
}

void GhostExchange::reverse(ParticleStore& ps) const {
  const Index n0 = ps.n_owned();
  for (Index k = 0; k < ps.n_ghost(); ++k) {
    const Index o = ps.ghost_owner[k];
    ps.force[o] += ps.force[n0 + k];
    ps.torque[o] += ps.torque[n0 + k];
  }
}

}  // namespace grainscale
