// Numbers in error messages, one way for the core: six significant digits.
#pragma once

#include <sstream>
#include <string>

namespace catenary_sim {

inline std::string fmt(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

}  // namespace catenary_sim
