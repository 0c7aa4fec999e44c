// Node settings: the private ROS parameters read once into a struct and validated; errors name
// the parameter, the value and the allowed range.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace ros {
class NodeHandle;
}
namespace XmlRpc {
class XmlRpcValue;
}

namespace catenary_sim {
struct Scene;

namespace ros_layer {

// Thrown for a missing required or invalid parameter.
class ParamError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A number as a user would write it (no trailing zeros), six significant digits: a limit.
std::string format_number(double v);
// A value as it was given, every digit it has: one just past a limit does not print as the limit.
std::string format_given(double v);
// Throws ParamError naming the parameter ~name, the value and the allowed range unless v is
// finite and in [lo, hi] (or (lo, hi] when lo_open).
void check_range(const char* name, double v, double lo, double hi, bool lo_open, const char* unit);
// Throws ParamError unless `frame` is a usable tf2 frame id (non-empty, no leading '/').
void check_frame_id(const char* name, const std::string& frame);
// "[lo, hi] unit" or "(lo, hi] unit", as check_range's messages write a range.
std::string range_text(double lo, double hi, bool lo_open, const char* unit);

// A parameter server value as given, for messages: 'text' (a string), 5 (an integer), ...
std::string describe_value(const XmlRpc::XmlRpcValue& v);

// The typed conversions of ParamReader, pure (gtest-able without a master). Each throws
// ParamError naming ~name, the value as given and `expected` unless `v` has the right type:
// a number is an integer or a double (rosparam stores 1 as an integer); a boolean only true or
// false (never 1 or "yes"); an integer only an integer; a string only a string (`_line_frame:=5` is an
// integer; a launch file's type="str" keeps a name of digits a string).
double param_number(const std::string& name, const XmlRpc::XmlRpcValue& v, const std::string& expected);
int param_integer(const std::string& name, const XmlRpc::XmlRpcValue& v, const std::string& expected);
bool param_bool(const std::string& name, const XmlRpc::XmlRpcValue& v);
std::string param_string(const std::string& name, const XmlRpc::XmlRpcValue& v, const std::string& expected);

// Private parameters set on the server that the node does not know: `all` are full parameter
// names (ros::param::getParamNames), `ns` the private namespace ("/catenary_sim"), `known` the
// names below it ("publish_rate", "hil/rate"). Returns the unknown ones below `ns`, relative.
std::vector<std::string> unknown_parameters(const std::vector<std::string>& all, const std::string& ns,
                                            const std::vector<std::string>& known);
// The warning for one unknown parameter: "unknown parameter ~vertical_scal (ignored); did you mean
// ~vertical_scale?" with the closest known name (edit distance, also to a known name's last part:
// ~rate suggests ~hil/rate), or the list of known names when none is close.
std::string unknown_parameter_warning(const std::string& name, const std::vector<std::string>& known);

// Typed reading of a node's private parameters, shared by the nodes. Constructed with every
// parameter the node knows, it first warns (ROS_WARN, once each) about any other parameter in
// the private namespace: a misspelt name is ignored, but never without a word. Each read leaves
// `out` unchanged when the parameter is not set and returns whether it was; a value of the wrong
// type throws ParamError (never a silent fallback to the default). Reading a name not in `known`
// is a programming error (std::logic_error).
class ParamReader {
 public:
  ParamReader(const ros::NodeHandle& private_nh, const char* who, std::vector<std::string> known);
  bool number(const std::string& name, double& out, const std::string& expected);
  bool integer(const std::string& name, int& out, const std::string& expected);
  bool boolean(const std::string& name, bool& out);
  bool text(const std::string& name, std::string& out, const std::string& expected);
  const std::vector<std::string>& known() const { return known_; }

 private:
  bool get(const std::string& name, XmlRpc::XmlRpcValue& v) const;
  const ros::NodeHandle& nh_;
  std::vector<std::string> known_;
};

// ~speed_kmh, as both nodes read it: a number (`expected` names the range), or an empty string
// (an empty launch argument, speed_kmh:="") for "not given". Returns whether it was given.
bool read_speed_kmh(ParamReader& r, const ros::NodeHandle& private_nh, std::optional<double>& out,
                    const std::string& expected);
// ~speed_kmh, when given, as the scene's train speed, within the scene's own limit (below the
// contact wire's wave speed); throws ParamError naming ~speed_kmh, as simulate_pass names --speed.
void apply_speed_kmh(const std::optional<double>& speed_kmh, Scene& scene);

// The lower bounds of the rates (Hz). The period 1/rate becomes a ros::WallDuration, whose
// seconds are an int32: anything below 1/2^31 Hz (e.g. 1e-10, 1e-300) threw out of the
// run loop and aborted the node. The bounds are those of cfg/Node.cfg (dynamic_reconfigure clamps
// to them), far above that limit: the pacing tick (publish_rate) is when commands, services and
// the end of the pass are handled, so at least once a second; a topic sent at shape_rate or
// marker_rate reaches a new subscriber (rviz, rosbag) within 10 s.
constexpr double kMinPublishRate = 1.0;
constexpr double kMinShapeRate = 0.1;
constexpr double kMinMarkerRate = 0.1;
constexpr double kMinVerticalScale = 0.1;  // cfg/Node.cfg
// The viewer wait and the strip chart's window, for both nodes that draw in rviz.
constexpr double kMaxWaitForViewer = 600.0;  // s
constexpr double kMinChartWindow = 0.5, kMaxChartWindow = 60.0;  // s of simulated time

enum class AtEnd { kStop, kLoop, kExit };

struct NodeParams {
  std::string scene;                // ~scene: scene YAML path (required)
  std::optional<double> speed_kmh;  // ~speed_kmh: overrides the scene's train speed, [0, 540] km/h
  double real_time_factor = 1.0;    // ~real_time_factor: [0, 1000]; 0 = as fast as possible
  double publish_rate = 200.0;      // ~publish_rate: Hz (wall clock), [1, 10000]
  double shape_rate = 10.0;         // ~shape_rate: Hz (wall clock) for wire_shape, [0.1, 1000]
  double marker_rate = 30.0;        // ~marker_rate: Hz (wall clock) for markers + the train_view tf, [0.1, 1000]
                                    //   (at most one per pacing tick: publish_rate bounds it)
  double shape_resolution = 1.0;    // ~shape_resolution: m between wire-shape samples, [0, 100] (0: every node)
  double vertical_scale = 10.0;     // ~vertical_scale: exaggeration of displacements in the markers, [0.1, 10000]
  double lateral_scale = 1.0;       // ~lateral_scale: stretch of the markers across the track (3-D line), [1, 100]
  std::string line_frame = "line";  // ~line_frame: fixed frame, x along the track, z up
  std::string view_pantograph;      // ~view_pantograph: the pantograph train_view (the camera, the strip
                                    //   chart) follows, by name (empty: the train front)
  AtEnd at_end = AtEnd::kStop;      // ~at_end: stop | loop | exit
  std::string stats_file;           // ~stats_file: JSON statistics written at the end (empty: none)
  std::string report_file;          // ~report_file: the pass report (HTML, scripts/pass_report) written at the
                                    //   end of each pass, its data files and pictures beside it (empty: none)
  bool publish_clock = true;        // ~publish_clock: publish rosgraph_msgs/Clock on /clock (simulated time,
                                    //   from 0, also while paused; pass.launch sets /use_sim_time with it)
  bool paused = false;              // ~paused: start paused (like gazebo's paused:=true); ~set_paused false starts
  // ~wait_for_recorder: s (wall) to wait for a subscriber of `pantograph_state` (the bag recorder of
  // pass.launch record:=true, which alone listens to it) so that the bag holds the pass's start
  double wait_for_recorder = 0.0;
  double wait_for_viewer = 0.0;     // ~wait_for_viewer: s (wall) to wait for a subscriber of `markers` (rviz)
                                    //   before the pass starts, [0, 600]; 0: no wait
  double max_acceleration = 1.0;    // ~max_acceleration: m/s^2 toward commanded speeds, [0, 20] (0: jump)
  double start_delay = 0.0;         // ~start_delay: s (wall) publishing the initial state before stepping, [0, 60]
                                    //   (lets rosbag record / rviz connect before a fast pass is over)
  bool strip_chart = true;          // ~strip_chart: draw the contact-force strip chart with the markers
  double chart_window = 5.0;        // ~chart_window: s of simulated time the strip chart shows, [0.5, 60]
};

// Throws ParamError for any value out of range (message: parameter, value, allowed range).
void validate(const NodeParams& p);

// Reads the private parameters of `private_nh` once, with the defaults above, and validates them;
// warns about unknown ones (ParamReader). Checks that ~stats_file can be written (the pass would
// otherwise run to its end for nothing): ParamError naming it, the path and the reason.
NodeParams load_params(const ros::NodeHandle& private_nh);

// Throws ParamError naming ~name, the path and the reason unless `path` (non-empty) can be
// written later (check_writable of core/output_files.hpp).
void check_output_param(const char* name, const std::string& path);

AtEnd parse_at_end(const std::string& s);  // throws ParamError
const char* to_string(AtEnd a);

// Loads the scene file and applies the overrides (speed). Throws ParamError naming ~scene for a
// scene that cannot be loaded (with the core's SceneError message).
Scene load_scene(const NodeParams& p);
// ~scene as a path to open: as given when it exists (roslaunch runs nodes in ROS_HOME), else a
// relative path in the package (config/...); throws ParamError saying so when neither has it.
std::string resolve_scene_path(const std::string& scene);

}  // namespace ros_layer
}  // namespace catenary_sim
