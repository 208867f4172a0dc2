// The registry of composed contact laws. The step loop is instantiated once per alternative
// (std::visit once per run() call, never per contact). Adding a law: one class with
// kHistorySize, prepare(MaterialTable), pair(mi, mj) and force(pair, input, history), and one
// entry in this variant.
#pragma once

#include <variant>

#include "contact/hertz_mindlin.hpp"

namespace grainscale {

using ContactLaw = std::variant<HertzMindlin>;

inline int history_size(const ContactLaw& law) {
  return std::visit([](const auto& l) { return std::decay_t<decltype(l)>::kHistorySize; }, law);
}

}  // namespace grainscale
