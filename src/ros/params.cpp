#include "catenary_sim/ros/params.hpp"

#include <ros/node_handle.h>

#include <cmath>
#include <sstream>

#include "catenary_sim/core/scene.hpp"

namespace catenary_sim {
namespace ros_layer {


std::string format_number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

void check_range(const char* name, double v, double lo, double hi, bool lo_open, const char* unit) {
  const bool ok = std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi;
  if (!ok)
    throw ParamError(std::string("parameter ~") + name + " = " + format_number(v) + " rejected: allowed " +
                     (lo_open ? "(" : "[") + format_number(lo) + ", " + format_number(hi) + "] " + unit);
}

void check_frame_id(const char* name, const std::string& frame) {
  if (frame.empty() || frame[0] == '/')
    throw ParamError(std::string("parameter ~") + name + " = '" + frame +
                     "' rejected: a non-empty frame id without a leading '/'");
}


AtEnd parse_at_end(const std::string& s) {
  if (s == "stop") return AtEnd::kStop;
  if (s == "loop") return AtEnd::kLoop;
  if (s == "exit") return AtEnd::kExit;
  throw ParamError("parameter ~at_end = '" + s + "' rejected: allowed stop, loop or exit");
}

const char* to_string(AtEnd a) {
  switch (a) {
    case AtEnd::kStop: return "stop";
    case AtEnd::kLoop: return "loop";
    case AtEnd::kExit: return "exit";
  }
  return "?";
}

void validate(const NodeParams& p) {
  if (p.scene.empty()) throw ParamError("parameter ~scene is required: path of a scene YAML file");
  if (p.speed_kmh) check_range("speed_kmh", *p.speed_kmh, 0.0, 540.0, false, "km/h");
  check_range("real_time_factor", p.real_time_factor, 0.0, 1000.0, false, "(0: as fast as possible)");
  check_range("publish_rate", p.publish_rate, 0.0, 10000.0, true, "Hz");
  check_range("shape_rate", p.shape_rate, 0.0, 1000.0, true, "Hz");
  check_range("marker_rate", p.marker_rate, 0.0, 1000.0, true, "Hz");
  check_range("shape_resolution", p.shape_resolution, 0.0, 100.0, false, "m (0: every node)");
  check_range("vertical_scale", p.vertical_scale, 0.0, 10000.0, true, "");
  check_range("max_acceleration", p.max_acceleration, 0.0, 20.0, false, "m/s^2 (0: no limit)");
  check_range("start_delay", p.start_delay, 0.0, 60.0, false, "s");
  check_range("wait_for_viewer", p.wait_for_viewer, 0.0, 600.0, false, "s (0: no wait)");
  check_frame_id("line_frame", p.line_frame);
}

NodeParams load_params(const ros::NodeHandle& nh) {
  NodeParams p;
  nh.param<std::string>("scene", p.scene, "");
  double speed = 0.0;
  if (nh.getParam("speed_kmh", speed)) {
    p.speed_kmh = speed;
  } else if (nh.hasParam("speed_kmh")) {
    // Present but not a number (e.g. an empty launch argument): treat "" as "not given".
    std::string s;
    if (!(nh.getParam("speed_kmh", s) && s.empty()))
      throw ParamError("parameter ~speed_kmh must be a number in [0, 540] km/h");
  }
  // Integers are accepted for the double parameters (rosparam stores "1" as int).
  auto number = [&](const char* name, double& out) {
    if (!nh.hasParam(name)) return;
    double d;
    int i;
    if (nh.getParam(name, d)) out = d;
    else if (nh.getParam(name, i)) out = i;
    else throw ParamError(std::string("parameter ~") + name + " must be a number");
  };
  number("real_time_factor", p.real_time_factor);
  number("publish_rate", p.publish_rate);
  number("shape_rate", p.shape_rate);
  number("marker_rate", p.marker_rate);
  number("shape_resolution", p.shape_resolution);
  number("vertical_scale", p.vertical_scale);
  number("max_acceleration", p.max_acceleration);
  number("start_delay", p.start_delay);
  number("wait_for_viewer", p.wait_for_viewer);
  nh.param<std::string>("line_frame", p.line_frame, p.line_frame);
  std::string at_end = to_string(p.at_end);
  nh.param<std::string>("at_end", at_end, at_end);
  p.at_end = parse_at_end(at_end);
  nh.param<std::string>("stats_file", p.stats_file, "");
  nh.param<bool>("publish_clock", p.publish_clock, p.publish_clock);
  nh.param<bool>("paused", p.paused, p.paused);
  validate(p);
  return p;
}

Scene load_scene(const NodeParams& p) {
  try {
    Scene scene = load_scene_file(p.scene);
    if (p.speed_kmh) {
      scene.train_speed = *p.speed_kmh / 3.6;
      validate(scene);
    }
    return scene;
  } catch (const SceneError& e) {
    throw ParamError("parameter ~scene = '" + p.scene + "': " + e.what());
  }
}

}  // namespace ros_layer
}  // namespace catenary_sim
