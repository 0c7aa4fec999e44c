// catenary_sim_node: live pantograph passes under a catenary (see README.md, launch/pass.launch).
#include <ros/ros.h>

#include <exception>

#include "catenary_sim/ros/node.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "catenary_sim");
  // Handles outlive the node object: destroying the last one shuts ROS (and its logging) down,
  // which would swallow the fatal message below.
  ros::NodeHandle nh, pnh("~");
  try {
    catenary_sim::ros_layer::SimulationNode node(nh, pnh);
    return node.run();
  } catch (const catenary_sim::ros_layer::ParamError& e) {
    ROS_FATAL("catenary_sim: %s", e.what());
    return 2;
  } catch (const std::exception& e) {  // (none expected: never an abort)
    ROS_FATAL("catenary_sim: %s", e.what());
    return 1;
  }
}
