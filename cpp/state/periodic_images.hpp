// The periodic images of a point: what a box query near a periodic boundary must also see.
#pragma once

#include "core/types.hpp"
#include "state/domain.hpp"

namespace grainscale {

// Calls visit(p) for every periodic image p of x (x itself included): positions may sit just
// outside the box until the next rebuild wraps them, so shifts of -L, 0, +L cover all cases.
template <class Visit>
void for_images(const Vec3& x, const Domain& domain, Visit visit) {
  Vec3 images[27];
  int n = 1;
  images[0] = x;
  for (int a = 0; a < 3; ++a) {
    if (!domain.periodic[a]) continue;
    const Real len = domain.hi[a] - domain.lo[a];
    const int m = n;
    for (int k = 0; k < m; ++k)
      for (Real s : {-len, len}) {
        Vec3 p = images[k];
        p[a] += s;
        images[n++] = p;
      }
  }
  for (int k = 0; k < n; ++k) visit(images[k]);
}

}  // namespace grainscale
