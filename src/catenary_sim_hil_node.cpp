// catenary_sim_hil_node: the catenary of a scene against real pantographs (hardware in the loop):
// hil/contact_force (or hil/contact_wrench) in, hil/contact_point out (see docs/hil.md,
// launch/hil.launch). The same node runs in a nodelet manager as catenary_sim/HilNodelet.
#include <sys/prctl.h>

#include "catenary_sim/ros/hil_node.hpp"
#include "catenary_sim/ros/node_main.hpp"

int main(int argc, char** argv) {
  // Timer slack of 1 us for every thread started from here (the loop thread sets it again, with
  // the real-time priority of ~hil/realtime_priority: HilNode::run).
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  return catenary_sim::ros_layer::node_main<catenary_sim::ros_layer::HilNode>(argc, argv, "catenary_sim_hil");
}
