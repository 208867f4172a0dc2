// Reading and writing named arrays of a LevelState (level/level_state.hpp): vectors as flat
// triples, integer arrays, and lookups that name the missing key.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "level/level_state.hpp"

namespace grainscale {
namespace state_io {

inline void put(LevelState& s, const std::string& key, const Vec3* v, std::size_t n) {
  auto& out = s.reals[key];
  out.resize(3 * n);
  for (std::size_t k = 0; k < n; ++k)
    for (int c = 0; c < 3; ++c) out[3 * k + c] = v[k][c];
}

inline void get(const LevelState& s, const std::string& key, Vec3* v, std::size_t n) {
  const auto& in = s.reals.at(key);
  if (in.size() != 3 * n)
    throw std::runtime_error("checkpoint array '" + key + "' has the wrong size");
  for (std::size_t k = 0; k < n; ++k) v[k] = Vec3(in[3 * k], in[3 * k + 1], in[3 * k + 2]);
}

template <class T>
void put_ints(LevelState& s, const std::string& key, const T* v, std::size_t n) {
  s.ints[key].assign(v, v + n);
}

inline const std::vector<double>& reals(const LevelState& s, const std::string& key) {
  auto it = s.reals.find(key);
  if (it == s.reals.end()) throw std::runtime_error("checkpoint lacks '" + key + "'");
  return it->second;
}

inline const std::vector<std::int64_t>& ints(const LevelState& s, const std::string& key) {
  auto it = s.ints.find(key);
  if (it == s.ints.end()) throw std::runtime_error("checkpoint lacks '" + key + "'");
  return it->second;
}

}  // namespace state_io
}  // namespace grainscale
