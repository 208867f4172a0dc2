// Error helpers: the core throws, never exits. The bindings map InvalidArgument to ValueError
// and every other std::exception to RuntimeError.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace grainscale {

class InvalidArgument : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// "Owner.parameter must be <constraint>, got <value>" — the project-wide message shape.
template <class T>
[[noreturn]] void throw_invalid(const std::string& parameter, const std::string& constraint,
                                const T& value) {
  std::ostringstream msg;
  msg.precision(17);
  msg << parameter << " must be " << constraint << ", got " << value;
  throw InvalidArgument(msg.str());
}

inline void require(bool condition, const std::string& message) {
  if (!condition) throw std::runtime_error(message);
}

}  // namespace grainscale
