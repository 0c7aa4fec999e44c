// The moving window's lengths ahead of and behind the pantographs (numerics.window).
#include "catenary_sim/core/model/window_lengths.hpp"

#include <algorithm>
#include <cmath>

#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

namespace {
// window: auto. A wave the pantograph sends ahead meets a reflector D ahead of it and its echo is
// back at the pantograph after 2 D / (c + V); one sent behind comes back from D behind after
// 2 D / (c - V). The window holds the reflectors whose echoes return within a memory time:
// D = (c +- V) T / 2. T measured in bench_window_lengths (BENCHMARKS.md: statistics within a few
// tenths of a percent of a generous window at 150-350 km/h): the echoes from behind are Doppler
// stretched to low frequencies, which the damping barely touches, so they are remembered longer.
constexpr double kMemoryAhead = 2.0, kMemoryBehind = 4.0;  // s
constexpr double kWindowMinSpans = 2.0;  // the droppers around the head and the joining span
}  // namespace

void window_lengths_for(const NumericsSpec& n, double c, double span, double speed, double* ahead, double* behind) {
  if (!n.window_auto) {
    *ahead = n.window_ahead;
    *behind = n.window_behind;
    return;
  }
  const double v = std::fabs(speed);
  *ahead = std::max(kWindowMinSpans * span, 0.5 * (c + v) * kMemoryAhead);
  *behind = std::max(kWindowMinSpans * span, 0.5 * std::max(0.0, c - v) * kMemoryBehind);
}

void window_lengths(const Model& m, double speed, double* ahead, double* behind) {
  window_lengths_for(m.scene.numerics, m.wave_speed, m.longest_span, speed, ahead, behind);
}

}  // namespace catenary_sim
