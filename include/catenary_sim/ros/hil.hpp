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
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/scene/scene.hpp"
#include "catenary_sim/core/engine/state.hpp"
#include "catenary_sim/hil/loop.hpp"
#include "catenary_sim/hil/realtime.hpp"
#include "catenary_sim/ros/params.hpp"

namespace catenary_sim {
namespace ros_layer {

// Private parameters of catenary_sim_hil_node (docs/hil.md).
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
  double wait_for_viewer = 0.0;     // ~wait_for_viewer: s (wall) the pass waits, line held, for rviz to
                                    //   subscribe to `markers` before it is armed, [0, 600] (0: no wait;
                                    //   with ~hil/auto_start true only)
  bool strip_chart = true;          // ~strip_chart: the contact-force strip chart with the markers
  double chart_window = 5.0;        // ~chart_window: s of simulated time the strip chart shows, [0.5, 60]
  double start_delay = 0.0;         // ~start_delay: s (wall) in which measurements are ignored and the
                                    //   initial state is published (lets recorders connect), [0, 60]
  double shape_rate = 10.0;         // ~shape_rate: Hz for wire_shape (only with a subscriber), [0.1, 100]
  double shape_resolution = 1.0;    // ~shape_resolution: m between wire_shape samples, [0, 100] (0: every node)
  double spin_wait = 0.0;           // ~hil/spin_wait: s; the loop blocks until this long before a due
                                    //   time (an expected arrival, the start of a window) and then polls
                                    //   its queue on the steady clock, [0, half a loop period]
  int realtime_priority = 0;        // ~hil/realtime_priority: > 0: SCHED_FIFO priority of the loop
                                    //   thread (and memory locked), [0, 99]
  bool lock_memory = false;         // ~hil/lock_memory: mlockall also without a real-time priority
  std::string cpus;                 // ~hil/cpus: CPUs of the loop thread, e.g. "3" or "2,3" (empty: any)
  double delay_compensation = 0.0;  // ~hil/delay_compensation: s, [0, 0.1]: the contact point sent is
                                    //   predicted this far ahead (the known loop delay)
  // catenary_sim_hil_udp_node only (the rig over UDP, udp_packets.h):
  std::string udp_bind = "0.0.0.0"; // ~hil/udp_bind: local IPv4 address
  int udp_port = 47800;             // ~hil/udp_port: local UDP port, [0, 65535]
  std::string udp_rig;              // ~hil/udp_rig: HOST:PORT of the rig (empty: the source of its
                                    //   newest valid measurement)
  std::string udp_allow;            // ~hil/udp_allow: senders that may be the rig, "A[:P],..." (empty: any)
};

// The real-time options of the parameters, named as parameters in errors.
hil::RealtimeOptions realtime_options(const HilParams& p);
// The loop's options of the parameters.
hil::LoopOptions loop_options(const HilParams& p);

// Throws ParamError naming the parameter, the value and the allowed range.
void validate_hil_params(const HilParams& p);
// Reads (ParamReader: typed, unknown names warned about), validates, and checks that ~stats_file
// and ~hil/report_file can be written. Throws ParamError.
HilParams load_hil_params(const ros::NodeHandle& private_nh);

// Loads the scene, applies ~speed_kmh and checks that it has an external pantograph. Throws
// ParamError naming ~scene.
Scene load_hil_scene(const HilParams& p);

// The ROS-free parts shared with the UDP loop (hil/loop.hpp).
using hil::HilTiming;
using hil::hold_ramp_force;
using hil::LatencyHistogram;
using hil::MeasurementHold;
using hil::external_pantographs;

// hil::hil_timing with its errors as ParamError (naming ~hil/rate and ~scene).
HilTiming hil_timing(double rate_hz, std::optional<double> scene_dt, double auto_dt);

// hil/contact_point for the current state: the motion of the wire under every external
// pantograph (contact_point_motion), its applied force, the simulation time and the header
// (`stamp`: the node gives the wall-clock time); the node fills mode, pass_count,
// measurement_step and measurement_age. `scratch` is reused between calls.
ContactPointArray to_contact_points(const Model& m, const State& s, const ros::Time& stamp, const std::string& frame,
                                    int steps_per_period, std::vector<ContactPointMotion>& scratch);

// True when every floating-point field is finite.
bool all_finite(const ContactPointArray& msg);

// hil/contact_point from the loop's frame (the header's stamp and frame given).
ContactPointArray to_contact_points(const Model& m, const hil::PointFrame& frame, const ros::Time& stamp,
                                    const std::string& frame_id);

}  // namespace ros_layer
}  // namespace catenary_sim
