// virtual_rig's loop: a simulated hardware-in-the-loop rig, so that catenary_sim_hil_node can run
// (and be tested) without hardware. It holds the lumped pantograph(s) of a scene (RigPantograph),
// imposes on each the wire motion it receives on hil/contact_point, and sends the contact force on
// hil/contact_force, paced on its own wall clock as a rig's controller would be. Runs as a process
// (virtual_rig: run() on the main thread) or as a nodelet (catenary_sim/VirtualRigNodelet: run()
// on a thread of its own, stop() ends it).
//
//   ~pantograph_scene  scene whose lumped pantographs have the names of the external ones (required)
//   ~rate              Hz, the rig's loop, [1, 20000] (0: the node's loop rate, from hil/contact_point)
//   ~extrapolate       true: between two contact points the wire height follows its path velocity
//                      (an actuator tracking the trajectory); false: held
//   ~report_file       JSON with the round trip (measurement sent -> the contact point that used it
//                      received) at exit; checked writable at start-up
//   ~transport         topics (hil/contact_point -> hil/contact_force) or udp: the packets of
//                      hil/udp_packets.h with catenary_sim_hil_udp_node (hil::UdpVirtualRig)
//   ~simulator         with udp: HOST:PORT of the simulator (default 127.0.0.1:47800)
// Typed and checked as the nodes' parameters (params.hpp: ParamReader); unknown ones are warned about.
#pragma once

#include <ros/callback_queue.h>
#include <ros/ros.h>

#include <atomic>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "catenary_sim/ContactPointArray.h"
#include "catenary_sim/core/scene/scene.hpp"
#include "catenary_sim/ros/hil.hpp"
#include "catenary_sim/ros/virtual_rig.hpp"

namespace catenary_sim {
namespace ros_layer {

class VirtualRig {
 public:
  // Reads the parameters and loads the scene; throws ParamError naming the parameter.
  VirtualRig(ros::NodeHandle nh, ros::NodeHandle pnh);
  // Runs the rig's loop until shutdown or stop(); prints (and writes) the report. Returns 0, 1
  // when ~report_file could not be written, or 2 when ~pantograph_scene cannot serve the
  // simulator's pantographs.
  int run();
  void stop() { stop_ = true; }

 private:
  void on_point(const ContactPointArray::ConstPtr& msg);
  void send();
  bool running() const { return ros::ok() && !stop_; }

  ros::NodeHandle nh_;
  ros::CallbackQueue queue_;
  ros::Subscriber sub_;
  ros::Publisher pub_;
  Scene scene_;
  double rate_ = 0.0;
  bool extrapolate_ = true;
  std::string report_file_;
  std::string transport_ = "topics";
  std::string simulator_ = "127.0.0.1:47800";
  int run_udp();
  // ~report_file (none: true); false when it could not be written.
  bool write_report(std::uint64_t sent, std::uint64_t missed, double wall, const LatencyHistogram& round_trip);
  std::string scene_name_;  // "parameter ~pantograph_scene = '<file>'" in messages
  bool failed_ = false;     // stopped because it cannot serve the simulator's pantographs
  std::string frame_;  // frame_id of the last contact point, sent back with the measurements
  hil::RigStepper stepper_;  // the pantographs and their stepping (shared with the UDP rig)
  bool have_ = false;
  std::uint64_t step_ = 0;
  double dt_ = 0.0;
  std::uint32_t steps_per_period_ = 1;
  std::uint64_t sent_ = 0, missed_ = 0;
  std::map<std::uint64_t, double> sent_at_;
  LatencyHistogram round_trip_;
  std::atomic<bool> stop_{false};
};

}  // namespace ros_layer
}  // namespace catenary_sim
