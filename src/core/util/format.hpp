// Numbers in error messages, one way for the core: six significant digits, or a given value whole.
#pragma once

#include <charconv>
#include <sstream>
#include <system_error>
#include <string>

#include "format_limit.hpp"

namespace catenary_sim {

inline std::string fmt(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

// A value as it was given (a command's, a parameter's, an argument's, in a refusal): its shortest
// round-trip form, every digit it has, so that one just past a limit (150.0000001 against 150)
// does not print as the limit itself. Computed values keep fmt's six digits.
inline std::string fmt_given(double v) {
  char buf[32];
  const std::to_chars_result r = std::to_chars(buf, buf + sizeof buf, v);
  return r.ec == std::errc() ? std::string(buf, r.ptr) : fmt(v);
}

}  // namespace catenary_sim
