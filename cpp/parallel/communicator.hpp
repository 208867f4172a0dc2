// Communicator: reductions across the ranks that run one level. Serial build: one rank and
// identity reductions. The MPI build wraps an MPI communicator behind the same interface.
#pragma once

#include <cstdint>

#include "core/types.hpp"

namespace grainscale {

class Communicator {
 public:
  int rank() const { return 0; }
  int size() const { return 1; }
  Real sum(Real v) const { return v; }
  Real max(Real v) const { return v; }
  std::int64_t sum(std::int64_t v) const { return v; }
};

}  // namespace grainscale
