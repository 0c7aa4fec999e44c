// Parameters of catenary_sim_hil_node: read once, validated; errors name the parameter, the value
// and the allowed range.
#include <ros/node_handle.h>

#include <cmath>
#include <sstream>

#include "catenary_sim/core/scene.hpp"
#include "catenary_sim/ros/hil.hpp"
#include "catenary_sim/ros/params.hpp"

namespace catenary_sim {
namespace ros_layer {

void validate_hil_params(const HilParams& p) {
  if (p.scene.empty())
    throw ParamError("parameter ~scene is required: path of a scene YAML file with a `type: external` pantograph");
  if (p.speed_kmh) check_range("speed_kmh", *p.speed_kmh, 0.0, 540.0, false, "km/h");
  check_range("hil/rate", p.rate, 1000.0, 10000.0, false, "Hz");
  const double period = 1.0 / p.rate;
  if (!std::isfinite(p.timeout) || p.timeout < 2.0 * period || p.timeout > 10.0)
    throw ParamError("parameter ~hil/timeout = " + format_number(p.timeout) + " s rejected: allowed [" + format_number(2.0 * period) +
                     ", 10] s (at least two loop periods of ~hil/rate = " + format_number(p.rate) + " Hz)");
  check_range("hil/hold_ramp", p.hold_ramp, 0.0, 60.0, false, "s (0: at once)");
  check_range("hil/hold_deceleration", p.hold_deceleration, 0.0, 50.0, false, "m/s^2 (0: at once)");
  check_range("publish_rate", p.publish_rate, 0.0, 1000.0, true, "Hz");
  check_range("marker_rate", p.marker_rate, 0.0, 100.0, true, "Hz");
  check_range("start_delay", p.start_delay, 0.0, 60.0, false, "s");
  check_range("shape_rate", p.shape_rate, 0.0, 100.0, true, "Hz");
  check_range("shape_resolution", p.shape_resolution, 0.0, 100.0, false, "m (0: every node)");
  if (!std::isfinite(p.spin_wait) || p.spin_wait < 0.0 || p.spin_wait > 0.5 * period)
    throw ParamError("parameter ~hil/spin_wait = " + format_number(p.spin_wait) + " s rejected: allowed [0, " +
                     format_number(0.5 * period) + "] s (at most half a loop period of ~hil/rate = " +
                     format_number(p.rate) + " Hz; 0: no spinning)");
  if (p.realtime_priority < 0 || p.realtime_priority > 99)
    throw ParamError("parameter ~hil/realtime_priority = " + std::to_string(p.realtime_priority) +
                     " rejected: allowed 0 (normal scheduling) to 99 (SCHED_FIFO priority)");
  check_frame_id("line_frame", p.line_frame);
}

HilParams load_hil_params(const ros::NodeHandle& nh) {
  HilParams p;
  nh.param<std::string>("scene", p.scene, "");
  auto number = [&](const char* name, double& out) {
    if (!nh.hasParam(name)) return false;
    double d;
    int i;
    std::string s;
    if (nh.getParam(name, d)) out = d;
    else if (nh.getParam(name, i)) out = i;
    else if (nh.getParam(name, s) && s.empty()) return false;  // an empty launch argument: not given
    else throw ParamError(std::string("parameter ~") + name + " must be a number");
    return true;
  };
  double speed = 0.0;
  if (number("speed_kmh", speed)) p.speed_kmh = speed;
  number("hil/rate", p.rate);
  number("hil/timeout", p.timeout);
  number("hil/hold_ramp", p.hold_ramp);
  number("hil/hold_deceleration", p.hold_deceleration);
  number("publish_rate", p.publish_rate);
  number("marker_rate", p.marker_rate);
  number("start_delay", p.start_delay);
  number("shape_rate", p.shape_rate);
  number("shape_resolution", p.shape_resolution);
  number("hil/spin_wait", p.spin_wait);
  if (nh.hasParam("hil/realtime_priority") && !nh.getParam("hil/realtime_priority", p.realtime_priority))
    throw ParamError("parameter ~hil/realtime_priority must be an integer in [0, 99]");
  if (nh.hasParam("hil/extrapolate") && !nh.getParam("hil/extrapolate", p.extrapolate))
    throw ParamError("parameter ~hil/extrapolate must be true or false");
  nh.param<std::string>("hil/report_file", p.report_file, "");
  nh.param<std::string>("stats_file", p.stats_file, "");
  nh.param<std::string>("line_frame", p.line_frame, p.line_frame);
  std::string at_end = to_string(p.at_end);
  nh.param<std::string>("at_end", at_end, at_end);
  p.at_end = parse_at_end(at_end);
  validate_hil_params(p);
  return p;
}

Scene load_hil_scene(const HilParams& p) {
  Scene scene;
  try {
    scene = load_scene_file(p.scene);
    if (p.speed_kmh) {
      scene.train_speed = *p.speed_kmh / 3.6;
      validate(scene);
    }
  } catch (const SceneError& e) {
    throw ParamError("parameter ~scene = '" + p.scene + "': " + e.what());
  }
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
