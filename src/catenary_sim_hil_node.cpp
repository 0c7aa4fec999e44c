// catenary_sim_hil_node: the catenary of a scene against real pantographs (hardware in the loop):
// hil/contact_force in, hil/contact_point out (see README "Hardware in the loop", launch/hil.launch).
#include <ros/ros.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>

#include <cerrno>
#include <cstring>

#include "catenary_sim/ros/hil_node.hpp"

int main(int argc, char** argv) {
  // Wake-ups within ~1 us of the requested time instead of the default 50 us timer slack (every
  // thread started from here inherits it).
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  ros::init(argc, argv, "catenary_sim_hil");
  ros::NodeHandle nh, pnh("~");
  // Optional real-time scheduling of the loop (needs CAP_SYS_NICE or an rtprio limit).
  int priority = 0;
  pnh.param("hil/realtime_priority", priority, 0);
  if (priority > 0) {
    sched_param sp{};
    sp.sched_priority = priority;
    if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0)
      ROS_WARN("catenary_sim_hil: ~hil/realtime_priority %d: SCHED_FIFO not granted (%s); running with normal "
               "scheduling", priority, std::strerror(errno));
    else if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
      ROS_WARN("catenary_sim_hil: mlockall failed (%s)", std::strerror(errno));
    else
      ROS_INFO("catenary_sim_hil: loop thread at SCHED_FIFO priority %d, memory locked", priority);
  }
  try {
    catenary_sim::ros_layer::HilNode node(nh, pnh);
    return node.run();
  } catch (const catenary_sim::ros_layer::ParamError& e) {
    ROS_FATAL("catenary_sim_hil: %s", e.what());
    return 2;
  }
}
