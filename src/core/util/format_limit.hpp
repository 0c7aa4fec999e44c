// A limit computed from the scene, printed so that the number shown is itself allowed (apart from
// format.hpp, whose fmt the scene reader's own would be ambiguous with).
#pragma once

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>

namespace catenary_sim {

// A limit computed from the scene, in a refusal: `digits` significant digits rounded toward the
// allowed side (up for "at least", down for "at most"), so that the number printed is itself
// allowed: 233.85102 is "at least 233.852", not the refused 233.851.
inline std::string fmt_limit(double v, bool at_least, int digits = 6) {
  auto print = [digits](double x) {
    std::ostringstream s;
    s.precision(digits);
    s << x;
    return s.str();
  };
  std::string out = print(v);
  if (!std::isfinite(v) || v == 0.0) return out;
  const double shown = std::strtod(out.c_str(), nullptr);
  if (at_least ? shown >= v : shown <= v) return out;
  const double step = std::pow(10.0, std::floor(std::log10(std::fabs(v))) - digits + 1);
  return print(at_least ? shown + step : shown - step);
}

}  // namespace catenary_sim
