#include "catenary_sim/hil/loop_timing.hpp"

#include "../core/util/format.hpp"  // the core's numbers in messages: one way for all

#include <algorithm>
#include <chrono>
#include <cmath>

namespace catenary_sim {
namespace hil {

double steady_now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string loop_rate_error(double rate, const std::string& name) {
  if (std::isfinite(rate) && rate >= kMinLoopRate && rate <= kMaxLoopRate) return "";
  return name + " = " + fmt(rate) + " rejected: allowed [" + fmt(kMinLoopRate) + ", " + fmt(kMaxLoopRate) + "] Hz";
}

HilTiming hil_timing(double rate, std::optional<double> scene_dt, double auto_dt, const std::string& rate_name,
                     const std::string& scene_name) {
  if (const std::string e = loop_rate_error(rate, rate_name); !e.empty()) throw HilError(e);
  HilTiming t;
  t.period = 1.0 / rate;
  if (scene_dt) {
    const double k = t.period / *scene_dt;
    const double kr = std::round(k);
    if (kr < 1.0 || std::fabs(k - kr) > 1e-6 * kr) {
      const int k_auto = static_cast<int>(std::ceil(t.period / *scene_dt - 1e-9));
      throw HilError("numerics.dt = " + fmt(*scene_dt) + " s of " + scene_name +
                     " does not divide the loop period " + fmt(t.period) + " s of " + rate_name + " = " +
                     fmt(rate) + " Hz: the period must be a whole number of core steps; use numerics.dt = "
                     "period / k, e.g. " + fmt(t.period / std::max(1, k_auto)) +
                     " s, or numerics.dt: auto (the loop then chooses it)");
    }
    t.steps_per_period = static_cast<int>(kr);
  } else {
    if (!(auto_dt > 0.0)) throw HilError(scene_name + ": the automatic dt is " + fmt(auto_dt) + " s");
    t.steps_per_period = static_cast<int>(std::ceil(t.period / auto_dt - 1e-9));
  }
  t.dt = t.period / t.steps_per_period;
  return t;
}

}  // namespace hil
}  // namespace catenary_sim
