// catenary_sim_hil_udp_node: hardware in the loop over UDP (include/catenary_sim/hil/udp_packets.h),
// the ROS topics for monitoring (docs/hil.md, "UDP").
#include <ros/ros.h>

#include <exception>

#include "catenary_sim/ros/hil_udp_node.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "catenary_sim_hil_udp");
  ros::NodeHandle nh, pnh("~");
  try {
    catenary_sim::ros_layer::HilUdpNode node(nh, pnh);
    return node.run();
  } catch (const catenary_sim::ros_layer::ParamError& e) {
    ROS_FATAL("catenary_sim_hil_udp: %s", e.what());
    return 2;
  } catch (const std::exception& e) {
    ROS_FATAL("catenary_sim_hil_udp: %s", e.what());
    return 1;
  }
}
