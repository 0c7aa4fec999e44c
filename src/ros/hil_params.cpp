// Parameters of catenary_sim_hil_node: read once, validated; errors name the parameter, the value
// and the allowed range.
#include <ros/node_handle.h>

#include <cmath>
#include <sstream>

#include "catenary_sim/core/scene/scene.hpp"
#include "catenary_sim/hil/loop.hpp"
#include "catenary_sim/ros/hil.hpp"
#include "catenary_sim/ros/params.hpp"

namespace catenary_sim {
namespace ros_layer {

void validate_hil_params(const HilParams& p) {
  if (p.scene.empty())
    throw ParamError("parameter ~scene is required: path of a scene YAML file with a `type: external` pantograph");
  if (p.speed_kmh) check_range("speed_kmh", *p.speed_kmh, 0.0, 3.6 * kMaxTrainSpeed, false, "km/h");
  if (const std::string e = hil::loop_rate_error(p.rate, "parameter ~hil/rate"); !e.empty()) throw ParamError(e);
  const double period = 1.0 / p.rate;
  if (!std::isfinite(p.timeout) || p.timeout < 2.0 * period || p.timeout > 10.0)
    throw ParamError("parameter ~hil/timeout = " + format_given(p.timeout) + " s rejected: allowed [" + format_number(2.0 * period) +
                     ", 10] s (at least two loop periods of ~hil/rate = " + format_number(p.rate) + " Hz)");
  check_range("hil/hold_ramp", p.hold_ramp, 0.0, 60.0, false, "s (0: at once)");
  // (the core's limit on the train's acceleration: Simulation::set_max_acceleration)
  check_range("hil/hold_deceleration", p.hold_deceleration, 0.0, Simulation::kMaxAcceleration, false, "m/s^2 (0: at once)");
  // (lower bounds as catenary_sim_node's: params.hpp)
  check_range("publish_rate", p.publish_rate, kMinPublishRate, 1000.0, false, "Hz");
  check_range("marker_rate", p.marker_rate, kMinMarkerRate, 100.0, false, "Hz");
  check_range("start_delay", p.start_delay, 0.0, 60.0, false, "s");
  check_range("shape_rate", p.shape_rate, kMinShapeRate, 100.0, false, "Hz");
  check_range("shape_resolution", p.shape_resolution, 0.0, 100.0, false, "m (0: every node)");
  if (!std::isfinite(p.spin_wait) || p.spin_wait < 0.0 || p.spin_wait > 0.5 * period)
    throw ParamError("parameter ~hil/spin_wait = " + format_given(p.spin_wait) + " s rejected: allowed [0, " +
                     format_number(0.5 * period) + "] s (at most half a loop period of ~hil/rate = " +
                     format_number(p.rate) + " Hz; 0: no spinning)");
  if (p.realtime_priority < 0 || p.realtime_priority > 99)
    throw ParamError("parameter ~hil/realtime_priority = " + std::to_string(p.realtime_priority) +
                     " rejected: allowed 0 (normal scheduling) to 99 (SCHED_FIFO priority)");
  check_frame_id("line_frame", p.line_frame);
  check_range("wait_for_viewer", p.wait_for_viewer, 0.0, kMaxWaitForViewer, false, "s (0: no wait)");
  check_range("chart_window", p.chart_window, kMinChartWindow, kMaxChartWindow, false, "s");
  check_range("hil/delay_compensation", p.delay_compensation, 0.0, 0.1, false, "s");
  if (p.udp_port < 0 || p.udp_port > 65535)
    throw ParamError("parameter ~hil/udp_port = " + std::to_string(p.udp_port) + " rejected: allowed 0 to 65535");
  if (const std::string e = hil::check_realtime(realtime_options(p)); !e.empty()) throw ParamError("parameter " + e);
}

hil::RealtimeOptions realtime_options(const HilParams& p) {
  hil::RealtimeOptions o;
  o.fifo_priority = p.realtime_priority;
  o.lock_memory = p.lock_memory || p.realtime_priority > 0;  // (a real-time loop also locks its memory)
  if (!p.cpus.empty()) {
    try {
      o.cpus = hil::parse_cpu_list(p.cpus, "~hil/cpus");
    } catch (const std::invalid_argument& e) {
      throw ParamError(std::string("parameter ") + e.what());
    }
  }
  o.lock_memory_name = "~hil/lock_memory";
  o.priority_name = "~hil/realtime_priority";
  o.cpus_name = "~hil/cpus";
  return o;
}

hil::LoopOptions loop_options(const HilParams& p) {
  hil::LoopOptions o;
  o.rate = p.rate;
  o.timeout = p.timeout;
  o.extrapolate = p.extrapolate;
  o.hold_ramp = p.hold_ramp;
  o.hold_deceleration = p.hold_deceleration;
  o.auto_start = p.auto_start;
  o.at_end = p.at_end == AtEnd::kLoop ? hil::EndAction::kLoop
             : p.at_end == AtEnd::kExit ? hil::EndAction::kExit : hil::EndAction::kStop;
  o.start_delay = p.start_delay;
  o.spin_wait = p.spin_wait;
  o.delay_compensation = p.delay_compensation;
  return o;
}

HilParams load_hil_params(const ros::NodeHandle& nh) {
  ParamReader r(nh, "catenary_sim_hil",
                {"scene", "speed_kmh", "hil/rate", "hil/timeout", "hil/extrapolate", "hil/hold_ramp",
                 "hil/hold_deceleration", "hil/report_file", "hil/realtime_priority", "hil/spin_wait", "hil/auto_start", "at_end",
                 "stats_file", "line_frame", "publish_rate", "marker_rate", "start_delay", "shape_rate",
                 "wait_for_viewer", "strip_chart", "chart_window",
                 "shape_resolution", "diagnostic_period", "hil/lock_memory", "hil/cpus", "hil/delay_compensation",
                 "hil/udp_bind", "hil/udp_port", "hil/udp_rig", "hil/udp_allow"});  // (the last read by diagnostic_updater)
  HilParams p;
  // (the ranges are checked by validate_hil_params; the type errors name them too)
  r.text("scene", p.scene, "the path of a scene YAML file");
  read_speed_kmh(r, nh, p.speed_kmh, "a number in " + range_text(0.0, 3.6 * kMaxTrainSpeed, false, "km/h"));
  r.number("hil/rate", p.rate, "a number in " + range_text(hil::kMinLoopRate, hil::kMaxLoopRate, false, "Hz"));
  r.number("hil/timeout", p.timeout, "a number of seconds in [2 loop periods, 10]");
  r.number("hil/hold_ramp", p.hold_ramp, "a number in [0, 60] s");
  r.number("hil/hold_deceleration", p.hold_deceleration,
           "a number in " + range_text(0.0, Simulation::kMaxAcceleration, false, "m/s^2"));
  r.number("publish_rate", p.publish_rate, "a number in " + range_text(kMinPublishRate, 1000.0, false, "Hz"));
  r.number("marker_rate", p.marker_rate, "a number in " + range_text(kMinMarkerRate, 100.0, false, "Hz"));
  r.number("start_delay", p.start_delay, "a number in [0, 60] s");
  r.number("shape_rate", p.shape_rate, "a number in " + range_text(kMinShapeRate, 100.0, false, "Hz"));
  r.number("shape_resolution", p.shape_resolution, "a number in [0, 100] m (0: every node)");
  r.number("hil/spin_wait", p.spin_wait, "a number of seconds in [0, half a loop period]");
  r.integer("hil/realtime_priority", p.realtime_priority, "an integer in [0, 99]");
  r.boolean("hil/extrapolate", p.extrapolate);
  r.boolean("hil/auto_start", p.auto_start);
  r.boolean("hil/lock_memory", p.lock_memory);
  r.number("wait_for_viewer", p.wait_for_viewer, "a number in " + range_text(0.0, kMaxWaitForViewer, false, "s (0: no wait)"));
  r.boolean("strip_chart", p.strip_chart);
  r.number("chart_window", p.chart_window, "a number in " + range_text(kMinChartWindow, kMaxChartWindow, false, "s"));
  r.text("hil/cpus", p.cpus, "CPU numbers, e.g. 3, 2,3 or 0-3 (empty: any)");
  r.number("hil/delay_compensation", p.delay_compensation, "a number in [0, 0.1] s");
  r.text("hil/udp_bind", p.udp_bind, "a numeric IPv4 address");
  r.integer("hil/udp_port", p.udp_port, "an integer in [0, 65535]");
  r.text("hil/udp_rig", p.udp_rig, "HOST:PORT (empty: the source of the rig's measurements)");
  r.text("hil/udp_allow", p.udp_allow, "IPv4 addresses with optional :PORT, separated by commas (empty: any sender)");
  r.text("hil/report_file", p.report_file, "a file path (empty: none)");
  r.text("stats_file", p.stats_file, "a file path (empty: none)");
  r.text("line_frame", p.line_frame, "a frame id");
  std::string at_end = to_string(p.at_end);
  r.text("at_end", at_end, "stop, loop or exit");
  p.at_end = parse_at_end(at_end);
  validate_hil_params(p);
  // Before the loop starts: a file that cannot be written is known now, not after the run.
  check_output_param("stats_file", p.stats_file);
  check_output_param("hil/report_file", p.report_file);
  return p;
}

Scene load_hil_scene(const HilParams& p) {
  Scene scene;
  try {
    scene = load_scene_file(p.scene);
  } catch (const SceneError& e) {
    throw ParamError("parameter ~scene = '" + p.scene + "': " + e.what());
  }
  apply_speed_kmh(p.speed_kmh, scene);
  bool external = false;
  for (const PantographSpec& ps : scene.pantographs) external = external || ps.external;
  if (!external)
    throw ParamError("parameter ~scene = '" + p.scene +
                     "': no pantograph of `type: external`; the hardware-in-the-loop node needs one (e.g. "
                     "config/reference_55m_hil.yaml)");
  return scene;
}

}  // namespace ros_layer
}  // namespace catenary_sim
