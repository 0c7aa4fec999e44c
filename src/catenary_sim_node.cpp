// catenary_sim_node: live pantograph passes under a catenary (see README.md, launch/pass.launch).
#include "catenary_sim/ros/node.hpp"
#include "catenary_sim/ros/node_main.hpp"

int main(int argc, char** argv) {
  return catenary_sim::ros_layer::node_main<catenary_sim::ros_layer::SimulationNode>(argc, argv, "catenary_sim");
}
