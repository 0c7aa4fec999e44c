// The main() of the nodes that run one node object (catenary_sim_node, catenary_sim_hil_node,
// catenary_sim_hil_udp_node): ros::init, the node made from its handles and run to its end.
#pragma once

#include <ros/ros.h>

#include <exception>

#include "catenary_sim/ros/params.hpp"

namespace catenary_sim {
namespace ros_layer {

// Returns the node's exit code; a bad parameter (ParamError) exits 2 and any other exception 1
// (none expected: never an abort), each after a FATAL line naming the node.
template <class Node>
int node_main(int argc, char** argv, const char* name) {
  ros::init(argc, argv, name);
  // Handles outlive the node object: destroying the last one shuts ROS (and its logging) down,
  // which would swallow the fatal message below.
  ros::NodeHandle nh, pnh("~");
  try {
    Node node(nh, pnh);
    return node.run();
  } catch (const ParamError& e) {
    ROS_FATAL("%s: %s", name, e.what());
    return 2;
  } catch (const std::exception& e) {
    ROS_FATAL("%s: %s", name, e.what());
    return 1;
  }
}

}  // namespace ros_layer
}  // namespace catenary_sim
