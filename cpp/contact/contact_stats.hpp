// Per-step contact statistics and an optional record of every touching contact (diagnostics,
// stress virial). Filled only on steps that ask for them, so the hot loop pays nothing else.
#pragma once

#include <cstdint>
#include <vector>

#include "core/types.hpp"

namespace grainscale {

struct ContactRecord {
  GlobalId id_i;
  GlobalId id_j;  // -1 - wall index for wall contacts
  Real overlap;
  Vec3 normal;
  Vec3 force;  // on i
  Index i;     // local index of i (owned) at the recording step
  Index j;     // local index of j (owned or ghost), -1 for a wall
};

struct ContactStats {
  std::int64_t contacts = 0;
  Real max_overlap_ratio = 0;  // overlap / smaller radius of the pair
  bool record = false;         // keep `records` (off by default: 80 bytes per contact)
  std::vector<ContactRecord> records;

  void clear() {
    contacts = 0;
    max_overlap_ratio = 0;
    records.clear();
    if (!record) records.shrink_to_fit();
  }
};

}  // namespace grainscale
