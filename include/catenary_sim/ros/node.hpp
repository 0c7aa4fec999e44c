// The live node: paces the core's fixed-dt steps to the wall clock, publishes contact forces,
// pantograph states, wire shapes, markers, tf and diagnostics, and takes commands and services.
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <dynamic_reconfigure/server.h>
#include <ros/ros.h>
#include <std_msgs/Float64.h>
#include <std_msgs/Float64MultiArray.h>
#include <std_srvs/SetBool.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/transform_broadcaster.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "catenary_sim/NodeConfig.h"
#include "catenary_sim/Step.h"
#include "catenary_sim/core/output/lateral_statistics.hpp"
#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "catenary_sim/ros/conversions.hpp"
#include "catenary_sim/ros/params.hpp"
#include "catenary_sim/ros/strip_chart.hpp"

namespace catenary_sim {
namespace ros_layer {

class SimulationNode {
 public:
  // Reads and validates the private parameters and loads the scene; throws ParamError.
  SimulationNode(ros::NodeHandle nh, ros::NodeHandle private_nh);

  // Runs the pacing loop until ros::ok() is false or the pass ends with at_end exit.
  // Returns the process exit code (0, or 1 after a divergence with at_end exit).
  int run();

  static constexpr int kMaxStepsPerCall = 100000;  // ~step service limit

 private:
  // Steps due by the wall clock (or as many as fit in one tick at real_time_factor 0).
  void advance(const ros::WallTime& tick_deadline);
  // Steps up to n times (stops at the end of the pass, a divergence or the deadline when given).
  std::int64_t do_steps(std::int64_t n, const ros::WallTime* deadline);
  void handle_end();
  void publish(bool force);
  void reanchor();
  void restart_recording();
  void report_statistics();
  // ~report_file: writes the pass's files beside it and starts scripts/pass_report (a child
  // process: the pictures take seconds, the pacing loop goes on); reap_report() collects it.
  void write_report();
  void reap_report(bool block);

  // The node's inputs (node_commands.cpp): commands, services and dynamic_reconfigure.
  void on_speed(const std_msgs::Float64::ConstPtr& msg);
  void on_uplift(const std_msgs::Float64MultiArray::ConstPtr& msg);
  bool on_reset(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  bool on_set_paused(std_srvs::SetBool::Request& req, std_srvs::SetBool::Response& res);
  bool on_step(Step::Request& req, Step::Response& res);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);
  void on_reconfigure(NodeConfig& config, uint32_t level);
  // Waits (wall clock) for a subscriber of `markers` up to ~wait_for_viewer, publishing the initial
  // state and /clock meanwhile.
  void wait_for_viewer();
  // Waits (wall clock) for a subscriber of `pantograph_state` up to ~wait_for_recorder, publishing
  // the initial state meanwhile: rosbag subscribes to all its topics at once, so the bag then
  // holds the pass from its first step however long rosbag took to start.
  void wait_for_recorder();
  // Both waits: publishing the initial state, up to wait_s for a subscriber of `pub`, then
  // settle_s more so that it has the initial state in hand.
  void wait_for_subscriber(const ros::Publisher& pub, double wait_s, const char* who, const char* param,
                           double settle_s);
  // Publishes `pass_status` (latched) when it changes: waiting, running, paused, ended, diverged.
  void publish_status();
  // LineState: the line around the train, on `line_state`.
  void publish_line_state(const ros::Time& stamp);
  // Contact-loss events per pantograph (a physics result, on `events`, not on /diagnostics).
  void track_contact_loss();
  // True while no step is taken (waiting, paused, ended, finished, diverged).
  bool holding() const;
  // A new /tf subscriber (rviz started during a pause) gets the held state's transforms, with the
  // hold's stamp, once: tf is only broadcast for a new time, and a repeated stamp would make every
  // other listener warn TF_REPEATED_DATA.
  void on_tf_subscriber(const ros::SingleSubscriberPublisher& pub);

  ros::NodeHandle nh_, pnh_;
  NodeParams params_;
  std::unique_ptr<Simulation> sim_;
  std::unique_ptr<PassRecorder> recorder_;
  std::unique_ptr<LateralRecorder> lateral_recorder_;  // a 3-D line's contact positions, blow-off, dewirements

  ros::Publisher contact_pub_, pantograph_pub_, shape_pub_, marker_pub_, clock_pub_, status_pub_, events_pub_,
      line_state_pub_, lateral_pub_, tf_hold_pub_, scene_pub_;
  ros::Subscriber speed_sub_, uplift_sub_;
  ros::ServiceServer reset_srv_, pause_srv_, step_srv_;
  tf2_ros::TransformBroadcaster tf_;
  diagnostic_updater::Updater updater_;
  std::unique_ptr<dynamic_reconfigure::Server<NodeConfig>> reconfigure_;
  ros::WallTime next_diagnostics_wall_;  // diagnostics on the wall clock (health, also while paused)
  std::string status_;                  // last published pass_status
  bool waiting_ = false;                // waiting for a viewer or ~start_delay
  // Per pantograph: in a contact loss since this simulated time and station (NaN: in contact).
  std::vector<double> loss_since_, loss_station_;
  int view_pantograph_ = -1;              // train_view follows this pantograph (-1: the train front)
  StripChart chart_;                      // samples within the chart window, statistics so far
  double achieved_rtf_ = 0.0;             // over the last diagnostics period (0 while holding)

  // Stamps are simulated time, as gazebo_ros does (docs/user_guide.md, "Time"): no offset.
  bool paused_ = false;
  bool ended_ = false;          // the end of the pass (or a divergence) has been handled
  bool exit_requested_ = false;
  int exit_code_ = 0;
  pid_t report_pid_ = -1;       // scripts/pass_report drawing the last pass's report, -1: none

  // Pacing.
  ros::WallTime wall_anchor_, wall_start_;
  double sim_anchor_ = 0.0;
  std::int64_t chunks_ = 0;    // pacing ticks that stepped (at least one step)
  std::int64_t overruns_ = 0;  // of those, ticks that could not take the steps due

  // Publishing bookkeeping.
  double last_published_time_ = -1.0;
  ros::WallTime last_shape_wall_, last_hold_wall_;
  ros::WallTime next_marker_wall_;   // markers are due at or after this wall time (marker_rate)
  double last_marker_time_ = -1.0;   // sim time of the last marker message
  ros::Time last_view_stamp_;        // stamp of the last train_view transform
  bool view_sent_ = false;           // a train_view transform has been broadcast (stamp 0 is a stamp)

  // Diagnostics.
  ros::WallTime last_command_wall_;
  bool have_command_ = false;
  ros::WallTime diag_wall_;
  double diag_sim_ = 0.0;
  std::int64_t diag_overruns_ = 0;
};

}  // namespace ros_layer
}  // namespace catenary_sim
