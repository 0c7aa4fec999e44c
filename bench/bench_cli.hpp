// The bench programs' command lines (CLI11, as the offline tools'): named positional arguments
// with their defaults in --help, each checked before anything runs, so that a bad value ends with
// CLI11's message naming the argument and what it allows, and a non-zero exit status.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "../src/tools/cli_checks.hpp"

namespace bench {

using catenary_sim::kFinite;

// Each repetition is a whole pass of every variant: a thousand is already hours of one table.
inline constexpr int kMaxRepetitions = 1000;

// The scene presets (numerics.preset), as the scene reader takes them.
inline const std::vector<std::string> kPresets = {"fast", "balanced", "accurate", "reference"};

// A number in (0, max] (CLI::PositiveNumber's range runs to the largest double, whose message is
// unreadable). Use as ->check(kFinite & positive_up_to(max)).
inline CLI::Validator positive_up_to(double max) {
  std::ostringstream allowed;
  allowed << "(0, " << max << "]";
  return CLI::Validator(
      [max, range = allowed.str()](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || *end != '\0' || !(v > 0.0 && v <= max)) return "Value " + text + " not in " + range;
        return std::string();
      },
      "NUMBER in " + allowed.str());
}

// `field=value`, as load_scene_file takes an override (refused there too, but only once a pass
// is built: here before anything runs).
inline const CLI::Validator kOverride(
    [](std::string& text) -> std::string {
      const std::size_t eq = text.find('=');
      if (eq == std::string::npos || eq == 0) return "'" + text + "' is not field=value, e.g. numerics.preset=fast";
      return std::string();
    },
    "FIELD=VALUE");

// [repetitions]: the runs of each variant, interleaved; the wall time is their median.
inline CLI::Option* add_repetitions(CLI::App& app, int& reps) {
  return app.add_option("repetitions", reps, "runs of each variant, interleaved (the wall time is their median)")
      ->check(CLI::Range(1, kMaxRepetitions))
      ->capture_default_str();
}

// [scene]: a scene file that exists (its default, the shipped reference scene, shown).
inline CLI::Option* add_scene(CLI::App& app, std::string& path) {
  return app.add_option("scene", path, "scene YAML")->check(CLI::ExistingFile)->capture_default_str();
}

// [field=value ...]: overrides of the scene, every remaining argument.
inline CLI::Option* add_overrides(CLI::App& app, std::vector<std::string>& overrides, const std::string& description) {
  return app.add_option("overrides", overrides, description)->check(kOverride);
}

}  // namespace bench
