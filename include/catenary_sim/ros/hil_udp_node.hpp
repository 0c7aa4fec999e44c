// catenary_sim_hil_udp_node: hardware in the loop over UDP (udp_packets.h) with the ROS topics
// kept for monitoring and recording. The loop (hil::HilLoop, the TCPROS node's) talks to the rig
// through hil::UdpLoopSkin on the main thread; each period's contact point also goes into a
// lock-free single-producer/single-consumer ring (hil::MonitorRing) that a publisher thread
// drains into hil/contact_point and /diagnostics, so that publishing never blocks the loop (a
// full ring drops and counts: `monitor dropped` in the diagnostics and the report). Services
// ~arm, ~set_paused, ~reset, ~stop and cmd/train_speed as the TCPROS node's; each pass's
// statistics logged and written to ~stats_file at its end by the publisher thread, as the TCPROS
// node's worker does. Parameters: those of
// catenary_sim_hil_node plus ~hil/udp_bind, ~hil/udp_port, ~hil/udp_rig (docs/hil.md, "UDP").
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <std_msgs/Float64.h>
#include <std_srvs/SetBool.h>
#include <std_srvs/Trigger.h>

#include <atomic>
#include <memory>
#include <mutex>
#include <thread>

#include "catenary_sim/hil/loop.hpp"
#include "catenary_sim/hil/udp_loop.hpp"
#include "catenary_sim/ros/hil.hpp"

namespace catenary_sim {
namespace ros_layer {

class HilUdpNode {
 public:
  // Reads and validates the parameters, opens the socket; throws ParamError.
  HilUdpNode(ros::NodeHandle nh, ros::NodeHandle pnh);
  ~HilUdpNode();
  int run();  // the loop on the calling thread until shutdown (or the end with at_end exit)

 private:
  void publisher();
  // The statistics of a pass that ended: logged and written to ~stats_file (publisher thread,
  // then at exit for the last one), as catenary_sim_hil_node's worker does.
  void report_finished_pass();
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);
  std::pair<bool, std::string> ask(hil::Request r, const char* service);

  ros::NodeHandle nh_, pnh_;
  HilParams params_;
  std::unique_ptr<hil::HilLoop> loop_;
  hil::MonitorRing ring_;
  std::unique_ptr<hil::UdpLoopSkin> skin_;
  std::atomic<bool> stop_publisher_{false};
  std::thread publisher_;
  double wall_offset_ = 0.0;  // ROS wall time - steady time
  // Publisher thread only.
  ros::Publisher point_pub_;
  diagnostic_updater::Updater updater_;
  hil::MonitorSample last_{};
  // A pass that ended, handed over by the loop thread.
  std::mutex pass_mu_;
  std::unique_ptr<PassRecorder> pass_recorder_;
  State pass_state_;
  std::int64_t pass_overruns_ = 0;
  std::atomic<bool> stats_failed_{false};
  std::uint64_t published_ = 0;
  // Control.
  ros::CallbackQueue ctrl_queue_;
  std::unique_ptr<ros::AsyncSpinner> ctrl_spinner_;
  ros::ServiceServer arm_srv_, pause_srv_, reset_srv_, stop_srv_;
  ros::Subscriber speed_sub_;
};

}  // namespace ros_layer
}  // namespace catenary_sim
