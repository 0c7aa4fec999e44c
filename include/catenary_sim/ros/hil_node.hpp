// catenary_sim_hil_node: the catenary of a scene against real pantographs (hardware in the loop).
//
// Force in, motion out. Once per loop period (~hil/rate, 1 to 10 kHz, a whole number of core
// steps) the node applies the newest measured contact force of every external pantograph
// (hil/contact_force), steps the core through the period and publishes the motion of the wire
// under each pantograph (hil/contact_point). The loop is paced on the wall clock: each period
// has a window one period wide; a fresh measurement that arrives inside it starts the steps at
// once (so the output follows the input by the computation time only), else the steps start at
// the window's end with the held measurement. The windows lock onto the arrivals of a rig that
// sends on its own clock at the same rate (at most 0.2 % of a period per period); a late answer
// that belongs to a period already run at its deadline starts nothing. Input older than
// ~hil/timeout puts the line into the safe hold (docs/hil.md).
//
// Slow publications (contact_force, pantograph_state, wire_shape, tf, markers, diagnostics, pass
// statistics) run on a second thread from snapshots of the state, so that the loop's period holds
// only the steps and the contact point.
//
// The rig's measurement comes as hil/contact_force (MeasuredContactForce, one total force per
// external pantograph) or, for a scene with one external pantograph, as hil/contact_wrench
// (geometry_msgs/WrenchStamped: force.z, z up, is the force the pantograph exerts on the wire).
//
// Control, as the pass node's: ~arm (start the pass with ~hil/auto_start false, or a new pass
// after the end), ~set_paused, ~reset, ~stop (services) and cmd/train_speed. They are served on a
// queue and a thread of their own; a request is handed to the loop thread, which carries it out
// at its next period and answers (the loop never waits for the control thread: it only
// try-locks the hand-over, once per period, when a request is pending).
//
// The node runs as a process (catenary_sim_hil_node: run() on the main thread) or as a nodelet
// (catenary_sim/HilNodelet: run() on a thread of its own, stop() ends it), e.g. with
// catenary_sim/VirtualRigNodelet in the same manager: the messages then pass as shared pointers.
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/WrenchStamped.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <std_msgs/Float64.h>
#include <std_srvs/SetBool.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/transform_broadcaster.h>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "catenary_sim/ContactPointArray.h"
#include "catenary_sim/MeasuredContactForce.h"
#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "catenary_sim/hil/loop.hpp"
#include "catenary_sim/ros/hil.hpp"
#include "catenary_sim/ros/strip_chart.hpp"

namespace catenary_sim {
namespace ros_layer {

// The ROS skin of the loop (hil::HilLoop: the periods, the held measurement, the safe hold,
// the control requests): hil/contact_force and hil/contact_wrench in, hil/contact_point out,
// services and cmd/train_speed handed to the loop, and the slow publications on a worker thread.
class HilNode : public hil::LoopSkin {
 public:
  // Reads and validates the parameters, loads the scene and chooses dt; throws ParamError.
  HilNode(ros::NodeHandle nh, ros::NodeHandle private_nh);
  ~HilNode() override;
  // Runs the loop until shutdown, stop() or the end of the pass with at_end exit. Returns the exit
  // code. The calling thread is the loop thread: with ~hil/realtime_priority it is made SCHED_FIFO.
  int run();
  // Ends run() within a loop period (from any thread).
  void stop() {
    stop_ = true;
    loop_->stop();
  }

  using Counters = hil::LoopCounters;

 private:
  using Mode = hil::Mode;
  using Request = hil::Request;

  // hil::LoopSkin (loop thread)
  bool running() override { return ros::ok() && !ros::isShuttingDown() && !stop_; }
  void receive(double until) override;
  void send(const hil::PointFrame& frame) override;
  void log(hil::LogLevel level, const std::string& text) override;
  void after_period(double now) override;
  void pass_ended(std::unique_ptr<PassRecorder> recorder, const State& state) override;

  // Construction, in this order: the loop of the scene (a bad setting is a ParamError naming the
  // parameter), the publishers, the rig's measurement subscriptions, the control services and
  // cmd/train_speed on their own queue and thread, and the start-up lines in the log.
  void make_loop(const Scene& scene);
  void advertise_outputs();
  void subscribe_measurements();
  void serve_control();
  void log_start(const Scene& scene) const;

  void on_measurement(const MeasuredContactForce::ConstPtr& msg);
  void on_wrench(const geometry_msgs::WrenchStamped::ConstPtr& msg);
  void snapshot(double t);
  void worker();
  // Worker thread: waits (up to 100 ms) for a new snapshot (then in wsnap_, *have set) or a pass
  // that has ended (moved to *finished); false once the worker is to stop.
  bool take_work(bool* have, std::unique_ptr<PassRecorder>* finished, State* finished_state);
  // The slow publications of wsnap_: contact_force, pantograph_state, tf, wire_shape, markers and
  // the strip chart, each at its own rate.
  void publish_snapshot(const Model& m);
  // The statistics of a pass that has ended: in the log and in ~stats_file.
  void report_pass(const Model& m, const PassRecorder& finished, const State& finished_state);
  // Arms the pass once rviz has subscribed to `markers` and drawn, or ~wait_for_viewer is over.
  void arm_when_viewer_ready();
  void publish_pantograph_state(const Model& m, const State& s, const ros::Time& stamp);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);
  bool write_report() const;  // false: ~hil/report_file could not be written (said on stderr)
  void stop_worker();         // after it has written the statistics of a pass that has ended

  // Control thread: services and cmd/train_speed.
  bool on_arm(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool on_set_paused(std_srvs::SetBool::Request& req, std_srvs::SetBool::Response& res);
  bool on_reset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool on_stop(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  void on_speed(const std_msgs::Float64::ConstPtr& msg);
  // Hands `r` to the loop and waits for its answer: (done, message), logged.
  std::pair<bool, std::string> ask_loop(Request r, const char* service);

  ros::NodeHandle nh_, pnh_;
  HilParams params_;
  std::unique_ptr<hil::HilLoop> loop_;
  std::vector<int> external_;

  // Loop thread.
  ros::CallbackQueue hil_queue_;
  ros::Subscriber force_sub_, wrench_sub_;
  std::atomic<bool> stop_{false};
  ros::Publisher point_pub_;
  double stamp_offset_ = 0.0;
  double next_snapshot_ = 0.0;

  // Snapshot for the worker thread (slow publications).
  struct Snapshot {
    State state;
    Mode mode = Mode::kWaiting;
    Counters counters;
    double age = -1.0, age_in_effect = -1.0;
    double latency[3] = {0, 0, 0};
    hil::JitterSummary jitter;
    bool diverged = false, dewired = false, armed = true, stopping = false, recovering = false;
    std::uint32_t pass_count = 0;
    double commanded_speed = 0.0;
  };
  std::mutex snap_mu_;
  std::condition_variable snap_cv_;
  Snapshot snap_;
  bool snap_new_ = false, stop_worker_ = false;
  std::unique_ptr<PassRecorder> finished_recorder_;  // a pass to report (under snap_mu_)
  State finished_state_;
  std::thread worker_;
  std::atomic<bool> stats_failed_{false};  // a ~stats_file write failed: the exit code becomes 1

  // Worker thread only.
  Snapshot wsnap_;
  ros::Publisher contact_pub_, pantograph_pub_, shape_pub_, marker_pub_;
  std::vector<ContactPointMotion> worker_scratch_;
  double next_shape_wall_ = 0.0;
  tf2_ros::TransformBroadcaster tf_;
  diagnostic_updater::Updater updater_;
  double last_tf_time_ = -1.0;
  ros::Time last_view_stamp_;
  double next_marker_wall_ = 0.0;
  StripChart chart_;             // the contact-force strip chart (~strip_chart)
  std::uint32_t chart_pass_ = 0;  // the pass the chart shows
  double chart_time_ = -1.0;      // simulated time of the newest snapshot charted
  // ~wait_for_viewer: wall time (steady clock) at which the pass is armed, 0 once it is; when rviz
  // subscribed (-1: not yet).
  double viewer_wait_until_ = 0.0, viewer_seen_ = -1.0;

  // Control: its own queue and thread (never the loop's).
  ros::CallbackQueue ctrl_queue_;
  std::unique_ptr<ros::AsyncSpinner> ctrl_spinner_;
  ros::ServiceServer arm_srv_, pause_srv_, reset_srv_, stop_srv_;
  ros::Subscriber speed_sub_;
};


}  // namespace ros_layer
}  // namespace catenary_sim
