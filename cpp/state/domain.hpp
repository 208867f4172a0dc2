// Simulation box with per-axis periodicity.
#pragma once

#include <array>

#include "core/errors.hpp"
#include "core/types.hpp"

namespace grainscale {

struct Domain {
  Vec3 lo = Vec3::Zero();
  Vec3 hi = Vec3::Ones();
  std::array<bool, 3> periodic{false, false, false};

  Domain() = default;
  Domain(const Vec3& lo_, const Vec3& hi_, const std::array<bool, 3>& periodic_)
      : lo(lo_), hi(hi_), periodic(periodic_) {
    for (int a = 0; a < 3; ++a)
      if (!(hi[a] > lo[a])) throw_invalid("Box.hi", "greater than Box.lo on every axis", hi[a]);
  }
  Vec3 length() const { return hi - lo; }
  bool inside(const Vec3& x, int axis) const { return x[axis] >= lo[axis] && x[axis] <= hi[axis]; }
};

}  // namespace grainscale
