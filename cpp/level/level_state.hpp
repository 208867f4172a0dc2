// LevelState: everything a Level needs to continue bit-identically, as named flat arrays
// (Python writes them to HDF5). The set-up (materials, contact law, interactions, wall shapes,
// inserters) is rebuilt by the user's script; `signature` lets a restart check it matches.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace grainscale {

struct LevelState {
  std::map<std::string, std::vector<double>> reals;
  std::map<std::string, std::vector<std::int64_t>> ints;
  std::map<std::string, std::string> texts;
};

}  // namespace grainscale
