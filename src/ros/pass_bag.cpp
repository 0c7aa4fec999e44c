#include "catenary_sim/ros/pass_bag.hpp"

#include <tf2_msgs/TFMessage.h>

#include "catenary_sim/ros/conversions.hpp"

namespace catenary_sim {
namespace ros_layer {

PassBag::PassBag(const std::string& path, const PassBagOptions& options) : o_(options) {
  bag_.open(path, rosbag::bagmode::Write);
}

void PassBag::write(const Model& m, const State& s) {
  const ros::Time stamp = sim_stamp(s.time, o_.stamp_offset);
  // The same topic names as the node publishes from the root namespace.
  if (first_ || o_.rate <= 0.0 || s.time + 1e-12 >= next_) {
    if (o_.rate > 0.0) next_ = (first_ ? s.time : next_) + 1.0 / o_.rate;
    bag_.write("/contact_force", stamp, to_contact_force(m, s, stamp, o_.line_frame));
    bag_.write("/pantograph_state", stamp, to_pantograph_state(m, s, stamp, o_.line_frame));
    tf2_msgs::TFMessage tf;
    tf.transforms = to_transforms(m, s, stamp, o_.line_frame);
    bag_.write("/tf", stamp, tf);
    messages_ += 3;
  }
  if (first_ || s.time + 1e-12 >= next_shape_) {
    next_shape_ = (first_ ? s.time : next_shape_) + 1.0 / o_.shape_rate;
    bag_.write("/wire_shape", stamp, to_wire_shape(m, s, o_.shape_resolution, stamp, o_.line_frame));
    ++messages_;
  }
  first_ = false;
}

}  // namespace ros_layer
}  // namespace catenary_sim
