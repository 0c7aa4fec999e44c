// virtual_rig: a simulated hardware-in-the-loop rig, so that catenary_sim_hil_node can run (and be
// tested) without hardware (the loop and its parameters: include/catenary_sim/ros/virtual_rig_loop.hpp).
// The same rig runs in a nodelet manager as catenary_sim/VirtualRigNodelet.
#include <ros/ros.h>
#include <sys/prctl.h>

#include <stdexcept>

#include "catenary_sim/ros/virtual_rig_loop.hpp"

int main(int argc, char** argv) {
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  ros::init(argc, argv, "virtual_rig");
  ros::NodeHandle nh, pnh("~");
  try {
    catenary_sim::ros_layer::VirtualRig rig(nh, pnh);
    return rig.run();
  } catch (const std::exception& e) {
    ROS_FATAL("virtual_rig: %s", e.what());
    return 2;
  }
}
