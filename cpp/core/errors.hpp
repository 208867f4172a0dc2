// Error helpers: the core throws, never exits. The bindings map InvalidArgument to ValueError
// and every other std::exception to RuntimeError.
#pragma once

#include <charconv>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace grainscale {

class InvalidArgument : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// "Owner.parameter must be <constraint>, got <value>" — the project-wide message shape.
// Shortest text that reads back to the same double (0.7 prints as "0.7").
inline std::string shortest(double v) {
  char buf[32];
  auto res = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, res.ptr);
}

template <class T>
[[noreturn]] void throw_invalid(const std::string& parameter, const std::string& constraint,
                                const T& value) {
  std::ostringstream msg;
  msg << parameter << " must be " << constraint << ", got ";
  if constexpr (std::is_floating_point_v<T>)
    msg << shortest(value);
  else
    msg << value;
  throw InvalidArgument(msg.str());
}

inline void require(bool condition, const std::string& message) {
  if (!condition) throw std::runtime_error(message);
}

}  // namespace grainscale
