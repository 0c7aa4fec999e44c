#include "catenary_sim/ros/params.hpp"

#include <ros/console.h>
#include <ros/node_handle.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "catenary_sim/core/output/output_files.hpp"
#include "catenary_sim/tools/package_files.hpp"
#include "catenary_sim/core/scene/scene.hpp"
#include "../core/util/edit_distance.hpp"
#include "../core/util/format.hpp"  // the core's numbers in messages: one way for all

namespace catenary_sim {
namespace ros_layer {


std::string format_number(double v) { return fmt(v); }
std::string format_given(double v) { return fmt_given(v); }

std::string range_text(double lo, double hi, bool lo_open, const char* unit) {
  std::string s = (lo_open ? "(" : "[") + format_number(lo) + ", " + format_number(hi) + "]";
  if (unit && *unit) s += std::string(" ") + unit;
  return s;
}

void check_range(const char* name, double v, double lo, double hi, bool lo_open, const char* unit) {
  const bool ok = std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi;
  if (!ok)
    throw ParamError(std::string("parameter ~") + name + " = " + format_given(v) + " rejected: allowed " +
                     range_text(lo, hi, lo_open, unit));
}

void check_frame_id(const char* name, const std::string& frame) {
  if (frame.empty() || frame[0] == '/')
    throw ParamError(std::string("parameter ~") + name + " = '" + frame +
                     "' rejected: a non-empty frame id without a leading '/'");
}


// ---------------------------------------------------------------------------------------------
// Typed reading

std::string describe_value(const XmlRpc::XmlRpcValue& v) {
  using XmlRpc::XmlRpcValue;
  switch (v.getType()) {
    case XmlRpcValue::TypeBoolean: return std::string(static_cast<const bool&>(v) ? "true" : "false") + " (a boolean)";
    case XmlRpcValue::TypeInt: return std::to_string(static_cast<const int&>(v)) + " (an integer)";
    case XmlRpcValue::TypeDouble: return format_given(static_cast<const double&>(v)) + " (a number)";
    case XmlRpcValue::TypeString: return "'" + static_cast<const std::string&>(v) + "' (a string)";
    case XmlRpcValue::TypeArray: return "a list";
    case XmlRpcValue::TypeStruct: return "a map";
    case XmlRpcValue::TypeDateTime: return "a date";
    case XmlRpcValue::TypeBase64: return "binary data";
    case XmlRpcValue::TypeInvalid: break;
  }
  return "an invalid value";
}

namespace {
[[noreturn]] void wrong_type(const std::string& name, const XmlRpc::XmlRpcValue& v, const std::string& expected) {
  throw ParamError("parameter ~" + name + " = " + describe_value(v) + " rejected: expected " + expected);
}
}  // namespace

double param_number(const std::string& name, const XmlRpc::XmlRpcValue& v, const std::string& expected) {
  if (v.getType() == XmlRpc::XmlRpcValue::TypeDouble) return static_cast<const double&>(v);
  if (v.getType() == XmlRpc::XmlRpcValue::TypeInt) return static_cast<const int&>(v);
  wrong_type(name, v, expected);
}

int param_integer(const std::string& name, const XmlRpc::XmlRpcValue& v, const std::string& expected) {
  if (v.getType() == XmlRpc::XmlRpcValue::TypeInt) return static_cast<const int&>(v);
  wrong_type(name, v, expected);
}

bool param_bool(const std::string& name, const XmlRpc::XmlRpcValue& v) {
  if (v.getType() == XmlRpc::XmlRpcValue::TypeBoolean) return static_cast<const bool&>(v);
  wrong_type(name, v, "true or false");
}

std::string param_string(const std::string& name, const XmlRpc::XmlRpcValue& v, const std::string& expected) {
  if (v.getType() == XmlRpc::XmlRpcValue::TypeString) return static_cast<const std::string&>(v);
  wrong_type(name, v, expected + " (a string; a name of digits: type=\"str\" in a launch file)");
}

std::vector<std::string> unknown_parameters(const std::vector<std::string>& all, const std::string& ns,
                                            const std::vector<std::string>& known) {
  std::string prefix = ns;
  if (prefix.empty() || prefix.back() != '/') prefix += '/';
  std::vector<std::string> out;
  for (const std::string& full : all) {
    if (full.size() <= prefix.size() || full.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string name = full.substr(prefix.size());
    if (std::find(known.begin(), known.end(), name) == known.end() &&
        std::find(out.begin(), out.end(), name) == out.end())
      out.push_back(name);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string unknown_parameter_warning(const std::string& name, const std::vector<std::string>& known) {
  std::string best;
  std::size_t best_d = std::string::npos;
  for (const std::string& k : known) {
    const auto slash = k.find_last_of('/');
    std::size_t d = edit_distance(name, k);
    if (slash != std::string::npos) d = std::min(d, edit_distance(name, k.substr(slash + 1)));
    if (d < best_d) {
      best_d = d;
      best = k;
    }
  }
  std::string s = "unknown parameter ~" + name + " (ignored); ";
  // Close: a typo or two, more in a long name.
  if (!best.empty() && best_d <= std::max<std::size_t>(2, name.size() / 3)) return s + "did you mean ~" + best + "?";
  s += "known parameters:";
  for (std::size_t i = 0; i < known.size(); ++i) s += (i ? ", ~" : " ~") + known[i];
  return s;
}

ParamReader::ParamReader(const ros::NodeHandle& nh, const char* who, std::vector<std::string> known)
    : nh_(nh), known_(std::move(known)) {
  std::vector<std::string> all;
  if (!nh_.getParamNames(all)) return;  // (no answer from the master: nothing to check)
  for (const std::string& name : unknown_parameters(all, nh_.getNamespace(), known_))
    ROS_WARN("%s: %s", who, unknown_parameter_warning(name, known_).c_str());
}

bool ParamReader::get(const std::string& name, XmlRpc::XmlRpcValue& v) const {
  if (std::find(known_.begin(), known_.end(), name) == known_.end())
    throw std::logic_error("ParamReader: parameter ~" + name + " is read but not in the list of known parameters");
  return nh_.hasParam(name) && nh_.getParam(name, v);
}

bool ParamReader::number(const std::string& name, double& out, const std::string& expected) {
  XmlRpc::XmlRpcValue v;
  if (!get(name, v)) return false;
  out = param_number(name, v, expected);
  return true;
}

bool ParamReader::integer(const std::string& name, int& out, const std::string& expected) {
  XmlRpc::XmlRpcValue v;
  if (!get(name, v)) return false;
  out = param_integer(name, v, expected);
  return true;
}

bool ParamReader::boolean(const std::string& name, bool& out) {
  XmlRpc::XmlRpcValue v;
  if (!get(name, v)) return false;
  out = param_bool(name, v);
  return true;
}

bool ParamReader::text(const std::string& name, std::string& out, const std::string& expected) {
  XmlRpc::XmlRpcValue v;
  if (!get(name, v)) return false;
  out = param_string(name, v, expected);
  return true;
}

void check_output_param(const char* name, const std::string& path) {
  if (path.empty()) return;
  try {
    check_writable(path);
  } catch (const OutputError& e) {
    throw ParamError(std::string("parameter ~") + name + " = '" + path + "' rejected: " + e.what());
  }
}

// ---------------------------------------------------------------------------------------------

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

namespace {
// The node's ranges, for validate() and the type errors of load_params().
struct Range {
  double lo, hi;
  bool lo_open;
  const char* unit;
  std::string text() const { return "a number in " + range_text(lo, hi, lo_open, unit); }
};
const Range kSpeed{0.0, 3.6 * kMaxTrainSpeed, false, "km/h"};  // the ceiling; the scene's wave speed in validate()
const Range kRealTimeFactor{0.0, 1000.0, false, "(0: as fast as possible)"};
const Range kPublishRate{kMinPublishRate, 10000.0, false, "Hz"};
const Range kShapeRate{kMinShapeRate, 1000.0, false, "Hz"};
const Range kMarkerRate{kMinMarkerRate, 1000.0, false, "Hz"};
const Range kShapeResolution{0.0, 100.0, false, "m (0: every node)"};
const Range kVerticalScale{kMinVerticalScale, 10000.0, false, ""};
const Range kLateralScale{1.0, 100.0, false, "(1: true scale)"};
const Range kMaxAcceleration{0.0, 20.0, false, "m/s^2 (0: no limit)"};
const Range kStartDelay{0.0, 60.0, false, "s"};
const Range kWaitForViewer{0.0, kMaxWaitForViewer, false, "s (0: no wait)"};
const Range kChartWindow{kMinChartWindow, kMaxChartWindow, false, "s"};

void check(const char* name, double v, const Range& r) { check_range(name, v, r.lo, r.hi, r.lo_open, r.unit); }
}  // namespace

void validate(const NodeParams& p) {
  if (p.scene.empty()) throw ParamError("parameter ~scene is required: path of a scene YAML file");
  if (p.speed_kmh) check("speed_kmh", *p.speed_kmh, kSpeed);
  check("real_time_factor", p.real_time_factor, kRealTimeFactor);
  check("publish_rate", p.publish_rate, kPublishRate);
  check("shape_rate", p.shape_rate, kShapeRate);
  check("marker_rate", p.marker_rate, kMarkerRate);
  check("shape_resolution", p.shape_resolution, kShapeResolution);
  check("vertical_scale", p.vertical_scale, kVerticalScale);
  check("lateral_scale", p.lateral_scale, kLateralScale);
  check("max_acceleration", p.max_acceleration, kMaxAcceleration);
  check("start_delay", p.start_delay, kStartDelay);
  check("wait_for_viewer", p.wait_for_viewer, kWaitForViewer);
  check("wait_for_recorder", p.wait_for_recorder, kWaitForViewer);
  check("chart_window", p.chart_window, kChartWindow);
  check_frame_id("line_frame", p.line_frame);
}

bool read_speed_kmh(ParamReader& r, const ros::NodeHandle& nh, std::optional<double>& out, const std::string& expected) {
  // An empty string (an empty launch argument, speed_kmh:="") means "not given"; any other
  // string is a type error.
  std::string s;
  if (nh.hasParam("speed_kmh") && nh.getParam("speed_kmh", s) && s.empty()) return false;
  double v = 0.0;
  if (!r.number("speed_kmh", v, expected + "; empty: the scene's speed")) return false;
  out = v;
  return true;
}

NodeParams load_params(const ros::NodeHandle& nh) {
  ParamReader r(nh, "catenary_sim",
                {"scene", "speed_kmh", "real_time_factor", "publish_rate", "shape_rate", "marker_rate",
                 "shape_resolution", "vertical_scale", "lateral_scale", "line_frame", "view_pantograph", "at_end", "stats_file", "report_file", "publish_clock",
                 "paused", "wait_for_viewer", "wait_for_recorder", "max_acceleration", "start_delay", "strip_chart", "chart_window",
                 "diagnostic_period"});  // (the last read by diagnostic_updater)
  NodeParams p;
  r.text("scene", p.scene, "the path of a scene YAML file");
  read_speed_kmh(r, nh, p.speed_kmh, kSpeed.text());
  r.number("real_time_factor", p.real_time_factor, kRealTimeFactor.text());
  r.number("publish_rate", p.publish_rate, kPublishRate.text());
  r.number("shape_rate", p.shape_rate, kShapeRate.text());
  r.number("marker_rate", p.marker_rate, kMarkerRate.text());
  r.number("shape_resolution", p.shape_resolution, kShapeResolution.text());
  r.number("vertical_scale", p.vertical_scale, kVerticalScale.text());
  r.number("lateral_scale", p.lateral_scale, kLateralScale.text());
  r.number("max_acceleration", p.max_acceleration, kMaxAcceleration.text());
  r.number("start_delay", p.start_delay, kStartDelay.text());
  r.number("wait_for_viewer", p.wait_for_viewer, kWaitForViewer.text());
  r.number("wait_for_recorder", p.wait_for_recorder, kWaitForViewer.text());
  r.text("line_frame", p.line_frame, "a frame id");
  r.text("view_pantograph", p.view_pantograph, "a pantograph's name (empty: the train front)");
  std::string at_end = to_string(p.at_end);
  r.text("at_end", at_end, "stop, loop or exit");
  p.at_end = parse_at_end(at_end);
  r.text("stats_file", p.stats_file, "a file path (empty: none)");
  r.text("report_file", p.report_file, "an HTML file path (empty: none)");
  r.boolean("publish_clock", p.publish_clock);
  r.boolean("paused", p.paused);
  r.boolean("strip_chart", p.strip_chart);
  r.number("chart_window", p.chart_window, kChartWindow.text());
  validate(p);
  check_output_param("stats_file", p.stats_file);
  if (!p.report_file.empty()) {
    // The report's directory holds its data files too: created, as simulate_pass --out is.
    const std::size_t slash = p.report_file.rfind('/');
    try {
      if (slash != std::string::npos && slash > 0) make_directories(p.report_file.substr(0, slash));
    } catch (const OutputError& e) {
      throw ParamError("parameter ~report_file = '" + p.report_file + "' rejected: " + e.what());
    }
  }
  check_output_param("report_file", p.report_file);
  return p;
}

std::string resolve_scene_path(const std::string& scene) {
  struct stat st {};
  if (scene.empty() || scene[0] == '/' || ::stat(scene.c_str(), &st) == 0) return scene;
  // roslaunch runs nodes in ROS_HOME: a path relative to the package (config/...) is looked for
  // there too.
  char cwd[4096] = "?";
  if (!::getcwd(cwd, sizeof cwd)) std::snprintf(cwd, sizeof cwd, "?");
  const std::string path = find_package_file(scene);
  if (path.empty())
    throw ParamError("parameter ~scene = '" + scene + "': no such file in the node's working directory " + cwd +
                     " (roslaunch runs nodes in ROS_HOME) nor in the package; give an absolute path, e.g. "
                     "scene:=$(rospack find catenary_sim)/config/reference_55m.yaml");
  ROS_INFO("catenary_sim: ~scene '%s' is not in the working directory %s: using the package's %s", scene.c_str(), cwd,
           path.c_str());
  return path;
}

void apply_speed_kmh(const std::optional<double>& speed_kmh, Scene& scene) {
  if (!speed_kmh) return;
  if (const TrainSpeedLimit limit = train_speed_limit(scene); !limit.allows(*speed_kmh / 3.6))
    throw ParamError("parameter ~speed_kmh = " + fmt_given(*speed_kmh) + " km/h: allowed " + limit.text());
  scene.train_speed = *speed_kmh / 3.6;
  try {
    validate(scene);
  } catch (const SceneError& e) {
    throw ParamError("parameter ~speed_kmh = " + fmt_given(*speed_kmh) + " km/h: " + e.what());
  }
}

Scene load_scene(const NodeParams& p) {
  const std::string path = resolve_scene_path(p.scene);
  Scene scene;
  try {
    scene = load_scene_file(path);
  } catch (const SceneError& e) {
    throw ParamError("parameter ~scene = '" + p.scene + "': " + e.what());
  }
  apply_speed_kmh(p.speed_kmh, scene);
  return scene;
}

}  // namespace ros_layer
}  // namespace catenary_sim
