// Node settings: the private ROS parameters read once into a struct and validated; errors name
// the parameter, the value and the allowed range.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>

namespace ros {
class NodeHandle;
}

namespace catenary_sim {
struct Scene;

namespace ros_layer {

// Thrown for a missing required or invalid parameter.
class ParamError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A number as a user would write it (no trailing zeros).
std::string format_number(double v);
// Throws ParamError naming the parameter ~name, the value and the allowed range unless v is
// finite and in [lo, hi] (or (lo, hi] when lo_open).
void check_range(const char* name, double v, double lo, double hi, bool lo_open, const char* unit);
// Throws ParamError unless `frame` is a usable tf2 frame id (non-empty, no leading '/').
void check_frame_id(const char* name, const std::string& frame);

enum class AtEnd { kStop, kLoop, kExit };

struct NodeParams {
  std::string scene;                // ~scene: scene YAML path (required)
  std::optional<double> speed_kmh;  // ~speed_kmh: overrides the scene's train speed, [0, 540] km/h
  double real_time_factor = 1.0;    // ~real_time_factor: [0, 1000]; 0 = as fast as possible
  double publish_rate = 200.0;      // ~publish_rate: Hz (wall clock), (0, 10000]
  double shape_rate = 10.0;         // ~shape_rate: Hz (wall clock) for wire_shape, (0, 1000]
  double marker_rate = 30.0;        // ~marker_rate: Hz (wall clock) for markers + the train_view tf, (0, 1000]
                                    //   (at most one per pacing tick: publish_rate bounds it)
  double shape_resolution = 1.0;    // ~shape_resolution: m between wire-shape samples, [0, 100] (0: every node)
  double vertical_scale = 10.0;     // ~vertical_scale: exaggeration of displacements in the markers, (0, 10000]
  std::string line_frame = "line";  // ~line_frame: fixed frame, x along the track, z up
  AtEnd at_end = AtEnd::kStop;      // ~at_end: stop | loop | exit
  std::string stats_file;           // ~stats_file: JSON statistics written at the end (empty: none)
  bool publish_clock = true;        // ~publish_clock: publish rosgraph_msgs/Clock on /clock (simulated time,
                                    //   from 0, also while paused; pass.launch sets /use_sim_time with it)
  bool paused = false;              // ~paused: start paused (like gazebo's paused:=true); ~set_paused false starts
  double wait_for_viewer = 0.0;     // ~wait_for_viewer: s (wall) to wait for a subscriber of `markers` (rviz)
                                    //   before the pass starts, [0, 600]; 0: no wait
  double max_acceleration = 1.0;    // ~max_acceleration: m/s^2 toward commanded speeds, [0, 20] (0: jump)
  double start_delay = 0.0;         // ~start_delay: s (wall) publishing the initial state before stepping, [0, 60]
                                    //   (lets rosbag record / rviz connect before a fast pass is over)
};

// Throws ParamError for any value out of range (message: parameter, value, allowed range).
void validate(const NodeParams& p);

// Reads the private parameters of `private_nh` once, with the defaults above, and validates them.
NodeParams load_params(const ros::NodeHandle& private_nh);

AtEnd parse_at_end(const std::string& s);  // throws ParamError
const char* to_string(AtEnd a);

// Loads the scene file and applies the overrides (speed). Throws ParamError naming ~scene for a
// scene that cannot be loaded (with the core's SceneError message).
Scene load_scene(const NodeParams& p);

}  // namespace ros_layer
}  // namespace catenary_sim
