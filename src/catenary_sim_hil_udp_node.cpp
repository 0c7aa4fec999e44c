// catenary_sim_hil_udp_node: hardware in the loop over UDP (include/catenary_sim/hil/udp_packets.h),
// the ROS topics for monitoring (docs/hil.md, "UDP").
#include "catenary_sim/ros/hil_udp_node.hpp"
#include "catenary_sim/ros/node_main.hpp"

int main(int argc, char** argv) {
  return catenary_sim::ros_layer::node_main<catenary_sim::ros_layer::HilUdpNode>(argc, argv, "catenary_sim_hil_udp");
}
