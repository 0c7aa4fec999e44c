// Writes a pass into a rosbag without a master (rosbag C++ API): the node's topics with the same
// conversions and simulation-time stamps, so an offline batch pass opens in the same tools
// (rqt_bag, rosbag play + rviz, Python rosbag) as a live recording.
#pragma once

#include <rosbag/bag.h>

#include <string>

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/engine/state.hpp"
#include "catenary_sim/core/output/statistics.hpp"

namespace catenary_sim {
namespace ros_layer {

struct PassBagOptions {
  double rate = 200.0;        // Hz for /contact_force, /pantograph_state and /tf (0: every step)
  double shape_rate = 10.0;   // Hz for /wire_shape (and /line_state)
  double shape_resolution = 1.0;  // m
  double stamp_offset = 1.0;  // s added to simulation time in every stamp (ros::Time(0) means "latest" to tf)
  std::string line_frame = "line";
};

class PassBag {
 public:
  // Opens (truncates) the bag; throws rosbag::BagException naming the path if it cannot.
  PassBag(const std::string& path, const PassBagOptions& options);
  // Call with the initial state and after every step; writes what is due at the rates. With the
  // pass's recorder (fed this state first), also /line_state at shape_rate, as the node does.
  void write(const Model& model, const State& state, const PassRecorder* recorder = nullptr);
  // The scene as the node publishes it (/catenary_sim/scene_yaml, latched on replay), at the
  // first stamp: the replay then needs no scene file.
  void write_scene(const std::string& scene_yaml);
  void close() { bag_.close(); }
  std::size_t messages() const { return messages_; }

 private:
  rosbag::Bag bag_;
  PassBagOptions o_;
  double next_ = 0.0, next_shape_ = 0.0;
  bool first_ = true;
  std::size_t messages_ = 0;
};

}  // namespace ros_layer
}  // namespace catenary_sim
