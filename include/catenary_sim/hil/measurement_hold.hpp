// The HIL loop's input between measurements: the newest valid one held (or extrapolated from
// the last two), and the safe hold's force ramp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace catenary_sim {
namespace hil {

// The newest valid measurement, held, with the previous one for the optional extrapolation.
// Times are seconds on one monotonic clock.
class MeasurementHold {
 public:
  explicit MeasurementHold(std::size_t pantographs = 0) : force_(pantographs), previous_(pantographs) {}
  // A valid measurement (one total force per external pantograph) that arrived at `arrival`;
  // `measured` is its own stamp (0: unknown, the arrival is used for the slope).
  void accept(const std::vector<double>& force, double arrival, double measured, std::uint64_t step);
  bool has_value() const { return count_ > 0; }
  std::uint64_t count() const { return count_; }
  double arrival() const { return arrival_; }
  std::uint64_t step() const { return step_; }
  // s since the newest arrival; +inf before the first.
  double age(double now) const { return count_ ? now - arrival_ : std::numeric_limits<double>::infinity(); }
  // Force (N) for pantograph i at time t: the newest value, or with `extrapolate` the line through
  // the last two measurements continued to t, at most `horizon` s past the newest arrival (the
  // newest value when there is no earlier one or their times do not increase).
  // Stamps whose clock does not run with the arrivals' (a unit slip: microseconds given as
  // nanoseconds) give slopes a thousandfold off: held instead (stamps_implausible()).
  double value(std::size_t i, double t, bool extrapolate, double horizon) const;
  // The stamped measurements' stamps advanced less than half or more than twice as fast as their
  // arrivals over at least kStampBaseline s since the first (or since the stamps went back).
  bool stamps_implausible() const { return implausible_; }
  static constexpr double kStampBaseline = 0.01;  // s: long enough to average the transport's jitter

 private:
  std::vector<double> force_, previous_;
  double arrival_ = 0.0, time_ = 0.0, previous_time_ = 0.0;
  double base_time_ = 0.0, base_arrival_ = 0.0;  // the stamped run's first measurement
  bool stamped_ = false, previous_stamped_ = false, implausible_ = false;
  std::uint64_t count_ = 0, step_ = 0;
};

// Safe hold: force ramped linearly from `from` to `to` over `ramp` s (0: `to` at once).
double hold_ramp_force(double from, double to, double elapsed, double ramp);

}  // namespace hil
}  // namespace catenary_sim
