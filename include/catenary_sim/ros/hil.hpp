// Hardware-in-the-loop mode (catenary_sim_hil_node): the pure parts, no node handle and no clock
// of their own, so that they are gtest-able without a master. The node is in hil_node.hpp.
//
// Causality: force in, motion out. The rig measures the contact force on a real pantograph and
// sends it on hil/contact_force (MeasuredContactForce); the node applies it to the catenary as an
// external pantograph (the core's distributed contact: a force-driven collector pushes the lowest
// contact wire(s) under it), steps the core, and publishes the motion of the wire under the
// pantograph on hil/contact_point (ContactPointArray), which the rig imposes on the pantograph.
#pragma once

#include <ros/time.h>

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "catenary_sim/ContactPointArray.h"
#include "catenary_sim/core/model.hpp"
#include "catenary_sim/core/scene.hpp"
#include "catenary_sim/core/state.hpp"
#include "catenary_sim/ros/params.hpp"

namespace catenary_sim {
namespace ros_layer {

// Private parameters of catenary_sim_hil_node (README "Hardware in the loop").
struct HilParams {
  std::string scene;                // ~scene: scene YAML with at least one `type: external` pantograph
  std::optional<double> speed_kmh;  // ~speed_kmh: overrides the scene's train speed, [0, 540] km/h
  double rate = 1000.0;             // ~hil/rate: Hz, loop rate on the wall clock, [1000, 10000]
  double timeout = 0.05;            // ~hil/timeout: s; older input puts the line into the safe hold,
                                    //   [2 loop periods, 10]
  bool extrapolate = false;         // ~hil/extrapolate: false holds the newest measurement; true
                                    //   extrapolates the line through the last two
  double hold_ramp = 0.5;           // ~hil/hold_ramp: s, force ramp to the static uplift in the safe
                                    //   hold, [0, 60] (0: at once)
  double hold_deceleration = 10.0;  // ~hil/hold_deceleration: m/s^2, the train stops at this rate in the
                                    //   safe hold and accelerates back after it, [0, 50] (0: at once)
  std::string report_file;          // ~hil/report_file: JSON with the loop's latency and overruns,
                                    //   written at exit (empty: none)
  bool auto_start = true;           // ~hil/auto_start: false: the pass starts only after ~arm
  AtEnd at_end = AtEnd::kStop;      // ~at_end: stop | loop | exit
  std::string stats_file;           // ~stats_file: pass statistics JSON at the end of each pass
  std::string line_frame = "line";  // ~line_frame
  double publish_rate = 100.0;      // ~publish_rate: Hz for contact_force and tf, [1, 1000]
  double marker_rate = 10.0;        // ~marker_rate: Hz for markers (only with a subscriber), [0.1, 100]
  double start_delay = 0.0;         // ~start_delay: s (wall) in which measurements are ignored and the
                                    //   initial state is published (lets recorders connect), [0, 60]
  double shape_rate = 10.0;         // ~shape_rate: Hz for wire_shape (only with a subscriber), [0.1, 100]
  double shape_resolution = 1.0;    // ~shape_resolution: m between wire_shape samples, [0, 100] (0: every node)
  double spin_wait = 0.0;           // ~hil/spin_wait: s; the loop blocks until this long before a due
                                    //   time (an expected arrival, the start of a window) and then polls
                                    //   its queue on the steady clock, [0, half a loop period]
  int realtime_priority = 0;        // ~hil/realtime_priority: > 0: SCHED_FIFO priority of the loop
                                    //   thread (and memory locked), [0, 99]
};

// Throws ParamError naming the parameter, the value and the allowed range.
void validate_hil_params(const HilParams& p);
// Reads (ParamReader: typed, unknown names warned about), validates, and checks that ~stats_file
// and ~hil/report_file can be written. Throws ParamError.
HilParams load_hil_params(const ros::NodeHandle& private_nh);

// Loads the scene, applies ~speed_kmh and checks that it has an external pantograph. Throws
// ParamError naming ~scene.
Scene load_hil_scene(const HilParams& p);

// The loop period and the core steps in it. The core's dt must divide the period: a scene with
// numerics.dt: auto gets the largest dt = period / k not above the automatic dt (`auto_dt`, the
// safety factor times the stability limit); an explicit numerics.dt must divide the period (to
// 1e-6 relative), else ParamError naming both values.
struct HilTiming {
  double period = 0.0;        // s
  int steps_per_period = 0;
  double dt = 0.0;            // s, period / steps_per_period exactly
};
HilTiming hil_timing(double rate_hz, std::optional<double> scene_dt, double auto_dt);

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
  double value(std::size_t i, double t, bool extrapolate, double horizon) const;

 private:
  std::vector<double> force_, previous_;
  double arrival_ = 0.0, time_ = 0.0, previous_time_ = 0.0;
  bool stamped_ = false, previous_stamped_ = false;
  std::uint64_t count_ = 0, step_ = 0;
};

// Safe hold: force ramped linearly from `from` to `to` over `ramp` s (0: `to` at once).
double hold_ramp_force(double from, double to, double elapsed, double ramp);

// Latencies (s) in 1 us bins up to 10 ms (longer ones count in the last bin and in max()).
// Fixed size: add() never allocates.
class LatencyHistogram {
 public:
  LatencyHistogram();
  void add(double seconds);
  std::uint64_t count() const { return count_; }
  double max() const { return max_; }
  double mean() const { return count_ ? sum_ / count_ : 0.0; }
  // q in [0, 1]: the upper edge of the bin holding the q-quantile (0 when empty).
  double quantile(double q) const;
  void clear();

 private:
  std::vector<std::uint64_t> bins_;
  std::uint64_t count_ = 0;
  double max_ = 0.0, sum_ = 0.0;
};

// hil/contact_point for the current state: the motion of the wire under every external
// pantograph (contact_point_motion), its applied force, the simulation time and the header
// (`stamp`: the node gives the wall-clock time); the node fills mode, pass_count,
// measurement_step and measurement_age. `scratch` is reused between calls.
ContactPointArray to_contact_points(const Model& m, const State& s, const ros::Time& stamp, const std::string& frame,
                                    int steps_per_period, std::vector<ContactPointMotion>& scratch);

// True when every floating-point field is finite.
bool all_finite(const ContactPointArray& msg);

// Indices of the external pantographs of a model, in scene order.
std::vector<int> external_pantographs(const Model& m);

}  // namespace ros_layer
}  // namespace catenary_sim
