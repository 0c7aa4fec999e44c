// catenary_sim_hil_node: the catenary of a scene against real pantographs (hardware in the loop):
// hil/contact_force (or hil/contact_wrench) in, hil/contact_point out (see README "Hardware in the
// loop", launch/hil.launch). The same node runs in a nodelet manager as catenary_sim/HilNodelet.
#include <ros/ros.h>

#include <exception>
#include <sys/prctl.h>

#include "catenary_sim/ros/hil_node.hpp"

int main(int argc, char** argv) {
  // Timer slack of 1 us for every thread started from here (the loop thread sets it again, with
  // the real-time priority of ~hil/realtime_priority: HilNode::run).
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  ros::init(argc, argv, "catenary_sim_hil");
  ros::NodeHandle nh, pnh("~");
  try {
    catenary_sim::ros_layer::HilNode node(nh, pnh);
    return node.run();
  } catch (const catenary_sim::ros_layer::ParamError& e) {
    ROS_FATAL("catenary_sim_hil: %s", e.what());
    return 2;
  } catch (const std::exception& e) {  // (none expected: never an abort)
    ROS_FATAL("catenary_sim_hil: %s", e.what());
    return 1;
  }
}
