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
// ~hil/timeout puts the line into the safe hold (README "Hardware in the loop").
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
#include "catenary_sim/core/statistics.hpp"
#include "catenary_sim/ros/hil.hpp"

namespace catenary_sim {
namespace ros_layer {

class HilNode {
 public:
  // Reads and validates the parameters, loads the scene and chooses dt; throws ParamError.
  HilNode(ros::NodeHandle nh, ros::NodeHandle private_nh);
  ~HilNode();
  // Runs the loop until shutdown, stop() or the end of the pass with at_end exit. Returns the exit
  // code. The calling thread is the loop thread: with ~hil/realtime_priority it is made SCHED_FIFO.
  int run();
  // Ends run() within a loop period (from any thread).
  void stop() { stop_ = true; }

  // Loop figures, also written to ~hil/report_file.
  struct Counters {
    std::int64_t batches = 0;        // loop periods that stepped
    std::int64_t triggered = 0;      // of those, started by a fresh measurement
    std::int64_t held = 0;           // running without a fresh measurement in the window (held input)
    std::int64_t hold_batches = 0;   // in the safe hold
    std::int64_t overruns = 0;       // the loop fell behind: a window closed before its steps began
    std::int64_t accepted = 0, rejected = 0;
    std::int64_t superseded = 0;     // replaced by a newer one before any period used them
    std::int64_t late = 0;           // answered an older contact point than the last published
    std::int64_t holds = 0;          // times the safe hold was entered
    std::int64_t relocks = 0;        // the windows were centred on an arrival again (after an overrun)
    double max_age_running = 0.0;    // s, oldest measurement used while running
  };

 private:
  enum class Mode { kWaiting, kRunning, kHold, kPaused, kEnded };
  // Requests of the services, carried out by the loop thread.
  enum class Request { kArm, kPause, kResume, kReset, kStop };

  void on_measurement(const MeasuredContactForce::ConstPtr& msg);
  void on_wrench(const geometry_msgs::WrenchStamped::ConstPtr& msg);
  // A measurement of `force` (one value per external pantograph, named `field`[i] in errors, or
  // `field` alone for a single value): validated whole, then held. False when rejected.
  bool accept(const double* force, double arrival, const ros::Time& stamp, std::uint64_t step, const char* field,
              bool indexed);
  void reject(const std::string& what);
  void wait_for_period(double w, double half, double& t);
  void batch(double t, bool triggered);
  void publish_point();
  void handle_end();
  void enter_hold(double t, double age);
  void leave_hold();
  void snapshot(double t);
  void worker();
  void publish_pantograph_state(const Model& m, const State& s, const ros::Time& stamp);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);
  bool write_report() const;  // false: ~hil/report_file could not be written (said on stderr)
  void stop_worker();         // after it has written the statistics of a pass that has ended
  static std::uint8_t mode_code(Mode m);
  static const char* mode_name(Mode m);

  // Control thread: services and cmd/train_speed.
  bool on_arm(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool on_set_paused(std_srvs::SetBool::Request& req, std_srvs::SetBool::Response& res);
  bool on_reset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool on_stop(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  void on_speed(const std_msgs::Float64::ConstPtr& msg);
  // Hands `r` to the loop thread and waits for its answer: (done, message).
  std::pair<bool, std::string> ask_loop(Request r, const char* service);
  // Loop thread: a pending speed command or request, at most one each per period.
  void poll_control();
  bool execute(Request r, std::string& message);
  void begin_stop();
  void new_pass();  // the line back at its initial static state, time running on, pass_count + 1
  bool stop_settled() const;

  ros::NodeHandle nh_, pnh_;
  HilParams params_;
  HilTiming timing_;
  std::unique_ptr<Simulation> sim_;
  std::vector<int> external_;
  double commanded_speed_ = 0.0;  // m/s, the scene's (or ~speed_kmh), then cmd/train_speed (loop thread)

  // Loop state (loop thread only).
  ros::CallbackQueue hil_queue_;
  ros::Subscriber force_sub_, wrench_sub_;
  std::atomic<bool> stop_{false};
  ros::Publisher point_pub_;
  Mode mode_ = Mode::kWaiting;
  bool armed_ = true;              // in kWaiting: the first valid measurement starts the pass
  Mode paused_from_ = Mode::kRunning;  // kPaused: the mode to return to
  bool stopping_ = false;          // kHold after ~stop: ends in kEnded once the line has settled
  bool recovering_ = false;        // accelerating back to the commanded speed after a safe hold
  double point_motion_ = 0.0;      // m/s, largest |velocity| and |path_velocity| in the last contact point
  MeasurementHold hold_;
  bool fresh_ = false;             // a valid measurement that may start a period (answers the last contact point)
  bool unused_ = false;            // the newest valid measurement has not been used by a period yet
  std::uint64_t published_step_ = 0;  // step of the last contact point published
  bool owed_ = false;              // the last period ran at its deadline without a measurement
  std::vector<double> accept_buf_;
  double age_in_effect_ = -1.0;    // s, age of the measurement used by the last batch
  std::uint64_t step_in_effect_ = 0;
  double hold_start_time_ = 0.0;   // s, simulation time when the safe hold began
  std::vector<double> hold_from_;  // N, per pantograph, force when it began
  bool diverged_ = false;
  bool exit_requested_ = false;
  int exit_code_ = 0;
  std::uint32_t pass_count_ = 0;
  double stamp_offset_ = 0.0;
  double started_ = 0.0;           // s (steady), first measurement
  std::vector<ContactPointMotion> scratch_;
  std::unique_ptr<PassRecorder> recorder_;
  Counters c_;
  LatencyHistogram latency_;       // measurement arrival -> its contact point published
  LatencyHistogram transport_;     // rig stamp -> arrival (same machine clocks)
  LatencyHistogram compute_;       // batch start -> contact point published
  LatencyHistogram wait_;          // measurement arrival -> the steps that use it start
  double next_snapshot_ = 0.0, next_quantiles_ = 0.0;
  double q_latency_[3] = {0, 0, 0};  // p50, p99, max for the diagnostics

  // Snapshot for the worker thread (slow publications).
  struct Snapshot {
    State state;
    Mode mode = Mode::kWaiting;
    Counters counters;
    double age = -1.0, age_in_effect = -1.0;
    double latency[3] = {0, 0, 0};
    bool diverged = false, armed = true, stopping = false, recovering = false;
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

  // Control: its own queue and thread (never the loop's); the hand-over of a request.
  ros::CallbackQueue ctrl_queue_;
  std::unique_ptr<ros::AsyncSpinner> ctrl_spinner_;
  ros::ServiceServer arm_srv_, pause_srv_, reset_srv_, stop_srv_;
  ros::Subscriber speed_sub_;
  std::mutex ctrl_mu_;                   // the loop only try-locks it
  std::condition_variable ctrl_cv_;
  std::atomic<bool> ctrl_posted_{false};  // a request waits for the loop
  Request ctrl_request_ = Request::kArm;  // (under ctrl_mu_, with the answer)
  bool ctrl_done_ = false, ctrl_ok_ = false;
  std::string ctrl_reply_;
  std::atomic<bool> loop_running_{false};
  std::atomic<bool> speed_posted_{false};  // a valid cmd/train_speed waits for the loop
  std::atomic<double> speed_command_{0.0};
};

// Loop-thread set-up: timer slack of 1 us (wake-ups on time), and with `realtime_priority` > 0
// SCHED_FIFO at that priority for the calling thread and all memory locked (needs CAP_SYS_NICE or
// an rtprio limit; refused: a warning, normal scheduling). `who` prefixes the log lines.
void prepare_loop_thread(int realtime_priority, const char* who);

}  // namespace ros_layer
}  // namespace catenary_sim
