// Command-line checks shared by the offline tools (CLI11).
#pragma once

#include <CLI/CLI.hpp>
#include <cmath>
#include <string>

namespace catenary_sim {

// CLI::Range alone lets NaN through (every comparison with NaN is false): a number option must
// also be finite. Use as ->check(kFinite & CLI::Range(lo, hi)).
inline const CLI::Validator kFinite(
    [](std::string& text) -> std::string {
      std::size_t used = 0;
      double v = 0.0;
      try {
        v = std::stod(text, &used);
      } catch (const std::exception&) {
        return "'" + text + "' is not a number";
      }
      if (used != text.size()) return "'" + text + "' is not a number";
      if (!std::isfinite(v)) return "'" + text + "' is not a finite number";
      return std::string();
    },
    "FINITE");

}  // namespace catenary_sim
