// The HIL loop's clock and period: the rates every transport accepts, the core steps in a
// period, and HilError for a setting of the loop that cannot be used.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>

namespace catenary_sim {
namespace hil {

// A setting of the loop that cannot be used; the message names it, the value and what is allowed.
class HilError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The loop rates (Hz) every HIL transport accepts (~hil/rate, catenary_sim_hil_udp --rate): a rig's
// force loop runs at 1 kHz at least to follow the contact force's content up to EN 50318's 20 Hz
// with room for its own filters; above 10 kHz a period (0.1 ms) is within the scheduling jitter of
// a general-purpose kernel (docs/benchmark_history.md).
constexpr double kMinLoopRate = 1000.0, kMaxLoopRate = 10000.0;
// "" when `rate` Hz is one the loop runs at, else "NAME = RATE rejected: allowed [1000, 10000] Hz"
// (`name`: how the caller's user names the rate).
std::string loop_rate_error(double rate, const std::string& name);

// The loop period and the core steps in it. The core's dt must divide the period: a scene with
// numerics.dt: auto gets the largest dt = period / k not above the automatic dt; an explicit
// numerics.dt must divide the period (to 1e-6 relative), else HilError naming both values
// (`rate_name`, `scene_name`: how the caller's user names them).
struct HilTiming {
  double period = 0.0;  // s
  int steps_per_period = 0;
  double dt = 0.0;  // s, period / steps_per_period exactly
};
HilTiming hil_timing(double rate_hz, std::optional<double> scene_dt, double auto_dt,
                     const std::string& rate_name = "parameter ~hil/rate", const std::string& scene_name = "~scene");

double steady_now();  // s on the monotonic clock every loop time is on

}  // namespace hil
}  // namespace catenary_sim
