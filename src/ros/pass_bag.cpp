#include "catenary_sim/ros/pass_bag.hpp"

#include <std_msgs/String.h>
#include <tf2_msgs/TFMessage.h>

#include <boost/make_shared.hpp>

#include "catenary_sim/ros/conversions.hpp"

namespace catenary_sim {
namespace ros_layer {

PassBag::PassBag(const std::string& path, const PassBagOptions& options) : o_(options) {
  bag_.open(path, rosbag::bagmode::Write);
}

void PassBag::write_scene(const std::string& scene_yaml) {
  std_msgs::String text;
  text.data = scene_yaml;
  // Latched, as the node advertises it: rosbag play then latches it too.
  // (a connection header of our own must name the type itself: rosbag then takes it as it is)
  auto header = boost::make_shared<ros::M_string>();
  (*header)["type"] = ros::message_traits::datatype<std_msgs::String>();
  (*header)["md5sum"] = ros::message_traits::md5sum<std_msgs::String>();
  (*header)["message_definition"] = ros::message_traits::definition<std_msgs::String>();
  (*header)["latching"] = "1";
  (*header)["callerid"] = "/catenary_sim";
  bag_.write("/catenary_sim/scene_yaml", sim_stamp(0.0, o_.stamp_offset), text, header);
  ++messages_;
}

void PassBag::write(const Model& m, const State& s, const PassRecorder* recorder) {
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
    if (recorder) {
      bag_.write("/line_state", stamp, to_line_state(m, s, *recorder, stamp, o_.line_frame));
      ++messages_;
    }
  }
  first_ = false;
}

}  // namespace ros_layer
}  // namespace catenary_sim
