#include "catenary_sim/hil/measurement_hold.hpp"

#include <algorithm>
#include <cmath>

namespace catenary_sim {
namespace hil {

void MeasurementHold::accept(const std::vector<double>& force, double arrival, double measured, std::uint64_t step) {
  previous_ = force_;
  previous_time_ = time_;
  force_ = force;
  arrival_ = arrival;
  // The measurement's own time when it has one, else its arrival: only differences are used.
  time_ = measured > 0.0 ? measured : arrival;
  previous_stamped_ = stamped_;
  stamped_ = measured > 0.0;
  // The stamps' clock against the arrivals', from the first of a run of stamped measurements (a
  // rig that restarts its clock, or sends unstamped ones between, starts a new run).
  if (!stamped_ || !previous_stamped_ || !(time_ > previous_time_)) {
    base_time_ = time_;
    base_arrival_ = arrival;
    implausible_ = false;
  } else if (arrival - base_arrival_ >= kStampBaseline) {
    const double rate = (time_ - base_time_) / (arrival - base_arrival_);
    implausible_ = !(rate >= 0.5 && rate <= 2.0);
  }
  step_ = step;
  ++count_;
}

double MeasurementHold::value(std::size_t i, double t, bool extrapolate, double horizon) const {
  if (i >= force_.size()) return 0.0;
  const double f = force_[i];
  // (a stamped and an unstamped measurement: two clocks, no slope)
  if (!extrapolate || count_ < 2 || stamped_ != previous_stamped_ || implausible_) return f;
  const double span = time_ - previous_time_;
  if (!(span > 0.0) || span > 1.0) return f;
  const double ahead = std::clamp(t - arrival_, 0.0, std::max(0.0, horizon));
  return f + (f - previous_[i]) / span * ahead;
}

double hold_ramp_force(double from, double to, double elapsed, double ramp) {
  if (!(ramp > 0.0) || elapsed >= ramp) return to;
  if (elapsed <= 0.0) return from;
  return from + (to - from) * (elapsed / ramp);
}

}  // namespace hil
}  // namespace catenary_sim
