// Basic numeric types shared by the whole core.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

namespace grainscale {

using Real = double;
using Vec3 = Eigen::Matrix<Real, 3, 1>;
using Index = std::int32_t;     // local particle index (owned then ghost)
using GlobalId = std::int64_t;  // global particle id, never reused

}  // namespace grainscale
