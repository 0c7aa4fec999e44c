#include "catenary_sim/ros/hil_node.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <tuple>
#include <chrono>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include <nlohmann/json.hpp>

#include "catenary_sim/ContactForceArray.h"
#include "catenary_sim/core/output_files.hpp"
#include "catenary_sim/ros/conversions.hpp"

namespace catenary_sim {
namespace ros_layer {

namespace {

// Steady (monotonic) clock in seconds: every loop time is on it.
double steady_now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Phase lock of the loop's windows onto the arrivals of a rig sending at the same rate: a gain
// per period on the offset of a triggering arrival from the window's centre, at most this share
// of a period per period: the rate stays within 0.2 % of ~hil/rate (a rig's crystal drifts far
// less), and a lost phase is found again within 250 periods.
constexpr double kLockGain = 0.05;
constexpr double kLockMax = 2e-3;
constexpr int kRelockPeriods = 16;
constexpr double kRecorderRowRate = 10.0;  // Hz, decimated rows of the pass recorder (unused here)
constexpr double kQuantilePeriod = 1.0;    // s (wall) between latency quantiles for the diagnostics
// ~stop: the safe hold ends the pass once the train stands, the force ramp is over and the wire
// under every pantograph moves slower than this (the actuator is then held where it is, a step in
// velocity below what a load cell's noise makes), or at the latest this long after the ramp.
constexpr double kSettledMotion = 2e-3;    // m/s
constexpr double kSettleMax = 5.0;         // s (simulation)
// How long a service waits for the loop to take its request: a period is at most 1 ms, but on a
// loaded machine the loop can fall far behind; a request not taken in time is withdrawn.
constexpr double kControlWait = 5.0;       // s (wall)

// An error at the end of the run: after a shutdown rosconsole no longer prints, so then on stderr.
void end_error(const std::string& what) {
  if (ros::ok() && !ros::isShuttingDown()) ROS_ERROR("%s", what.c_str());
  else std::fprintf(stderr, "[ERROR] %s\n", what.c_str());
}

}  // namespace

void prepare_loop_thread(int priority, const char* who) {
  // Wake-ups within ~1 us of the requested time instead of the default 50 us timer slack (threads
  // started from this one inherit it).
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  if (priority <= 0) return;
  sched_param sp{};
  sp.sched_priority = priority;
  if (pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) != 0)
    ROS_WARN("%s: ~hil/realtime_priority %d: SCHED_FIFO not granted; running with normal scheduling", who, priority);
  else if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
    ROS_WARN("%s: mlockall failed (%s)", who, std::strerror(errno));
  else
    ROS_INFO("%s: loop thread at SCHED_FIFO priority %d, memory locked", who, priority);
}

std::uint8_t HilNode::mode_code(Mode m) {
  switch (m) {
    case Mode::kWaiting: return ContactPointArray::WAITING;
    case Mode::kRunning: return ContactPointArray::RUNNING;
    case Mode::kHold: return ContactPointArray::SAFE_HOLD;
    case Mode::kPaused: return ContactPointArray::PAUSED;
    case Mode::kEnded: return ContactPointArray::ENDED;
  }
  return ContactPointArray::ENDED;
}

const char* HilNode::mode_name(Mode m) {
  switch (m) {
    case Mode::kWaiting: return "waiting";
    case Mode::kRunning: return "running";
    case Mode::kHold: return "safe hold";
    case Mode::kPaused: return "paused";
    case Mode::kEnded: return "ended";
  }
  return "ended";
}

HilNode::HilNode(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(nh), pnh_(pnh), params_(load_hil_params(pnh)), updater_(nh, pnh) {
  Scene scene = load_hil_scene(params_);
  try {
    // The automatic dt of this scene decides how many steps a period holds (hil_timing).
    double auto_dt = 0.0;
    if (!scene.numerics.dt) auto_dt = build_model(scene).dt;
    timing_ = hil_timing(params_.rate, scene.numerics.dt, auto_dt);
    scene.numerics.dt = timing_.dt;
    sim_ = std::make_unique<Simulation>(scene);
  } catch (const SceneError& e) {
    throw ParamError("parameter ~scene = '" + params_.scene + "': " + e.what());
  }
  const Model& m = sim_->model();
  external_ = external_pantographs(m);
  commanded_speed_ = scene.train_speed;
  std::string err;
  if (!sim_->set_max_acceleration(params_.hold_deceleration, &err)) throw ParamError("parameter ~hil/hold_deceleration: " + err);
  hold_ = MeasurementHold(external_.size());
  accept_buf_.assign(external_.size(), 0.0);
  hold_from_.assign(m.pantographs.size(), 0.0);
  recorder_ = std::make_unique<PassRecorder>(m, kRecorderRowRate);
  recorder_->record(m, sim_->state());
  stamp_offset_ = std::floor(ros::WallTime::now().toSec());

  // One second of contact points queued per subscriber: a subscriber stalled for a few periods (a
  // loaded machine) gets them late instead of losing them; roscpp drops the oldest of a fuller
  // queue, and a rig that loses one integrates its pantograph against an extrapolated wire for
  // two periods, a recorder a hole in its series (seen in test_ros_hil_loop at 2 kHz on a loaded
  // 2-core machine with the former 10: 41 lost in a pass).
  point_pub_ = nh_.advertise<ContactPointArray>("hil/contact_point", static_cast<std::uint32_t>(std::ceil(params_.rate)));
  contact_pub_ = nh_.advertise<ContactForceArray>("contact_force", 10);
  pantograph_pub_ = nh_.advertise<PantographStateArray>("pantograph_state", 10);
  shape_pub_ = nh_.advertise<WireShapeArray>("wire_shape", 2);
  marker_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("markers", 2);
  // The rig's measurements on a queue of their own, waited on by the loop; TCP_NODELAY: no
  // Nagle delay on the small messages (the hint is also applied to the rig's end of the socket).
  ros::SubscribeOptions so = ros::SubscribeOptions::create<MeasuredContactForce>(
      "hil/contact_force", 100, [this](const MeasuredContactForce::ConstPtr& msg) { on_measurement(msg); },
      ros::VoidPtr(), &hil_queue_);
  so.transport_hints = ros::TransportHints().tcpNoDelay();
  force_sub_ = nh_.subscribe(so);
  // The same measurement as a wrench (a load cell's usual message), on the same queue.
  ros::SubscribeOptions wo = ros::SubscribeOptions::create<geometry_msgs::WrenchStamped>(
      "hil/contact_wrench", 100, [this](const geometry_msgs::WrenchStamped::ConstPtr& msg) { on_wrench(msg); },
      ros::VoidPtr(), &hil_queue_);
  wo.transport_hints = ros::TransportHints().tcpNoDelay();
  wrench_sub_ = nh_.subscribe(wo);
  armed_ = params_.auto_start;
  // Control on a queue and a thread of its own: the loop never serves it (see the header).
  auto trigger = [this](const char* name, bool (HilNode::*f)(std_srvs::Trigger::Request&, std_srvs::Trigger::Response&)) {
    ros::AdvertiseServiceOptions o = ros::AdvertiseServiceOptions::create<std_srvs::Trigger>(
        name, [this, f](std_srvs::Trigger::Request& q, std_srvs::Trigger::Response& r) { return (this->*f)(q, r); },
        ros::VoidConstPtr(), &ctrl_queue_);
    return pnh_.advertiseService(o);
  };
  arm_srv_ = trigger("arm", &HilNode::on_arm);
  reset_srv_ = trigger("reset", &HilNode::on_reset);
  stop_srv_ = trigger("stop", &HilNode::on_stop);
  ros::AdvertiseServiceOptions po = ros::AdvertiseServiceOptions::create<std_srvs::SetBool>(
      "set_paused", [this](std_srvs::SetBool::Request& q, std_srvs::SetBool::Response& r) { return on_set_paused(q, r); },
      ros::VoidConstPtr(), &ctrl_queue_);
  pause_srv_ = pnh_.advertiseService(po);
  ros::SubscribeOptions vo = ros::SubscribeOptions::create<std_msgs::Float64>(
      "cmd/train_speed", 10, [this](const std_msgs::Float64::ConstPtr& msg) { on_speed(msg); }, ros::VoidPtr(),
      &ctrl_queue_);
  speed_sub_ = nh_.subscribe(vo);
  ctrl_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &ctrl_queue_);
  ctrl_spinner_->start();

  updater_.setHardwareID("catenary_sim_hil/" + scene.name);
  updater_.add("hardware in the loop", this, &HilNode::diagnose);

  std::string names;
  for (int p : external_) names += (names.empty() ? "" : ", ") + m.pantographs[p].name;
  ROS_INFO("catenary_sim_hil: scene %s: %d DOFs, external pantograph(s) %s; loop %g Hz (period %g ms) = %d step(s) "
           "of dt %.6g ms (stability limit %.4g ms); speed %.1f km/h; timeout %g s; %s; at_end %s",
           scene.name.c_str(), m.n_dof, names.c_str(), params_.rate, timing_.period * 1e3, timing_.steps_per_period,
           m.dt * 1e3, m.dt_critical * 1e3, scene.train_speed * 3.6, params_.timeout,
           params_.extrapolate ? "linear extrapolation" : "newest measurement held", to_string(params_.at_end));
  if (armed_)
    ROS_INFO("catenary_sim_hil: waiting for the first measurement on %s%s (the line holds its static state)",
             force_sub_.getTopic().c_str(),
             external_.size() == 1 ? (" or " + wrench_sub_.getTopic()).c_str() : "");
  else
    ROS_INFO("catenary_sim_hil: ~hil/auto_start false: the line holds its static state until `rosservice call %s`; "
             "the pass then starts with the first measurement", arm_srv_.getService().c_str());
  worker_ = std::thread([this] { worker(); });
}

HilNode::~HilNode() {
  {
    std::lock_guard<std::mutex> l(ctrl_mu_);
    loop_running_ = false;
  }
  ctrl_cv_.notify_all();
  if (ctrl_spinner_) ctrl_spinner_->stop();  // (before the services and their queue go)
  stop_worker();
}

// ---- Control: services and commands (control thread) ----

void HilNode::on_speed(const std_msgs::Float64::ConstPtr& msg) {
  const double v = msg->data;
  if (const std::string e = speed_command_error(v); !e.empty()) {
    ROS_ERROR_THROTTLE(1.0, "catenary_sim_hil: %s; command ignored", e.c_str());
    return;
  }
  if (const std::string w = speed_warning(sim_->model(), v); !w.empty())  // (the model is never changed)
    ROS_WARN_THROTTLE(5.0, "catenary_sim_hil: %s", w.c_str());
  speed_command_ = v;
  speed_posted_ = true;  // (the loop takes the newest at its next period)
}

std::pair<bool, std::string> HilNode::ask_loop(Request r, const char* service) {
  std::unique_lock<std::mutex> l(ctrl_mu_);
  if (!loop_running_) return {false, "refused: the loop is not running (starting up or shutting down); nothing changed"};
  ctrl_request_ = r;
  ctrl_done_ = false;
  ctrl_posted_ = true;
  ctrl_cv_.wait_for(l, std::chrono::duration<double>(kControlWait), [this] { return ctrl_done_ || !loop_running_; });
  if (!ctrl_done_) {
    ctrl_posted_ = false;  // withdrawn: the loop has not taken it (it takes it under ctrl_mu_)
    return {false, "refused: the loop did not take the request within " + format_number(kControlWait) +
                       " s (far behind its schedule, or stopping); nothing changed"};
  }
  if (ctrl_ok_) ROS_INFO("catenary_sim_hil: ~%s: %s", service, ctrl_reply_.c_str());
  else ROS_WARN("catenary_sim_hil: ~%s: %s", service, ctrl_reply_.c_str());
  return {ctrl_ok_, ctrl_reply_};
}

bool HilNode::on_arm(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  std::tie(res.success, res.message) = ask_loop(Request::kArm, "arm");
  return true;
}

bool HilNode::on_set_paused(std_srvs::SetBool::Request& req, std_srvs::SetBool::Response& res) {
  std::tie(res.success, res.message) = ask_loop(req.data ? Request::kPause : Request::kResume, "set_paused");
  return true;
}

bool HilNode::on_reset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  std::tie(res.success, res.message) = ask_loop(Request::kReset, "reset");
  return true;
}

bool HilNode::on_stop(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  std::tie(res.success, res.message) = ask_loop(Request::kStop, "stop");
  return true;
}

// ---- Control (loop thread) ----

void HilNode::poll_control() {
  if (speed_posted_.exchange(false)) {
    commanded_speed_ = speed_command_;
    // (in the safe hold the train keeps stopping: leave_hold applies the commanded speed)
    const bool holding = mode_ == Mode::kHold || (mode_ == Mode::kPaused && paused_from_ == Mode::kHold);
    std::string err;
    if (!holding) sim_->set_target_speed(commanded_speed_, &err);  // (checked: cannot fail)
    if (mode_ == Mode::kWaiting) {
      // Not started: the pass starts at the commanded speed (the line is at its initial static
      // state; reset() with the static force needs no new static solve and changes nothing else).
      for (int p : external_) sim_->set_external_force(p, sim_->state().uplift[p], nullptr);
      sim_->reset(true);
    }
  }
  if (!ctrl_posted_) return;
  std::unique_lock<std::mutex> l(ctrl_mu_, std::try_to_lock);
  if (!l.owns_lock() || !ctrl_posted_) return;  // (the control thread holds it for a moment: next period)
  ctrl_ok_ = execute(ctrl_request_, ctrl_reply_);
  ctrl_done_ = true;
  ctrl_posted_ = false;
  l.unlock();
  ctrl_cv_.notify_all();
}

bool HilNode::execute(Request r, std::string& msg) {
  const std::string now = stopping_ ? "stopping (~stop)" : mode_ == Mode::kPaused
      ? std::string(paused_from_ == Mode::kHold ? "paused (in the safe hold)" : "paused")
      : mode_ == Mode::kWaiting ? (armed_ ? "waiting for the first measurement" : "waiting for ~arm")
      : mode_ == Mode::kEnded ? (diverged_ ? "ended (diverged)" : "ended") : mode_name(mode_);
  auto refuse = [&](const std::string& why) {
    msg = "refused: the pass is " + now + "; " + why;
    return false;
  };
  char t[64];
  std::snprintf(t, sizeof t, "t = %.4f s", sim_->state().time);
  switch (r) {
    case Request::kArm:
      if (mode_ == Mode::kWaiting) {
        if (armed_) return refuse("already armed: it starts with the first valid measurement");
        armed_ = true;
        msg = "armed: the pass starts with the first valid measurement";
        return true;
      }
      if (mode_ == Mode::kEnded) {
        new_pass();
        mode_ = Mode::kWaiting;
        armed_ = true;
        hold_ = MeasurementHold(external_.size());  // (the last pass's measurements start nothing)
        fresh_ = unused_ = owed_ = false;
        age_in_effect_ = -1.0;
        step_in_effect_ = 0;
        msg = "pass " + std::to_string(pass_count_) + " armed: the line is at its initial static state at " + t +
              " (time keeps running); it starts with the first valid measurement";
        return true;
      }
      return refuse("~arm starts a pass that has not started or has ended (~stop ends it, ~reset restarts it)");
    case Request::kPause:
      if (stopping_) return refuse("it ends by itself");
      if (mode_ == Mode::kRunning || mode_ == Mode::kHold) {
        paused_from_ = mode_;
        mode_ = Mode::kPaused;
        msg = std::string("paused at ") + t + ": the line is held, the contact point repeats (velocities 0); "
              "~set_paused false resumes";
        return true;
      }
      if (mode_ == Mode::kPaused) return refuse("already paused");
      return refuse(mode_ == Mode::kEnded ? "nothing to pause (~arm for a new pass)" : "nothing to pause yet");
    case Request::kResume:
      if (mode_ != Mode::kPaused) return refuse("not paused");
      mode_ = paused_from_;
      msg = std::string("resumed at ") + t + (mode_ == Mode::kHold ? " in the safe hold" : "");
      return true;
    case Request::kReset:
      if (stopping_) return refuse("~arm after its end starts a new pass");
      if (mode_ == Mode::kRunning || mode_ == Mode::kHold || mode_ == Mode::kPaused) {
        new_pass();
        msg = "new pass " + std::to_string(pass_count_) + " from the start at " + t + " (time keeps running)" +
              (mode_ == Mode::kPaused ? "; still paused" : "");
        return true;
      }
      return refuse(mode_ == Mode::kEnded ? "~arm starts a new pass" : "nothing to reset (it has not started)");
    case Request::kStop:
      if (stopping_) return refuse("already stopping");
      if (mode_ == Mode::kRunning || mode_ == Mode::kHold || mode_ == Mode::kPaused) {
        begin_stop();
        msg = std::string("stopping at ") + t + ": safe hold (the train stops at " +
              format_number(params_.hold_deceleration) + " m/s^2, the force ramps to the static uplift over " +
              format_number(params_.hold_ramp) + " s), then ENDED with the statistics written once the line has settled";
        return true;
      }
      return refuse(mode_ == Mode::kEnded ? "already ended" : "nothing to stop (it has not started)");
  }
  return false;
}

void HilNode::begin_stop() {
  if (mode_ == Mode::kPaused) mode_ = paused_from_;
  stopping_ = true;
  recovering_ = false;
  if (mode_ == Mode::kHold) return;  // a safe hold already: it goes on, and then ends the pass
  mode_ = Mode::kHold;
  hold_start_time_ = sim_->state().time;
  for (int p : external_) hold_from_[p] = sim_->state().external_force[p];
  std::string err;
  sim_->set_target_speed(0.0, &err);
}

bool HilNode::stop_settled() const {
  const State& s = sim_->state();
  const double elapsed = s.time - hold_start_time_;
  if (s.speed > 0.0 || elapsed < params_.hold_ramp) return false;
  return point_motion_ < kSettledMotion || elapsed >= params_.hold_ramp + kSettleMax;
}

void HilNode::new_pass() {
  // As at_end loop: the static force first (no new static solve in reset), the clock running on.
  for (int p : external_) sim_->set_external_force(p, sim_->state().uplift[p], nullptr);
  const bool holding = mode_ == Mode::kHold || (mode_ == Mode::kPaused && paused_from_ == Mode::kHold);
  std::string err;
  sim_->set_target_speed(holding ? 0.0 : commanded_speed_, &err);  // (reset starts at the target speed)
  sim_->reset(true);
  ++pass_count_;
  recorder_ = std::make_unique<PassRecorder>(sim_->model(), kRecorderRowRate);
  recorder_->record(sim_->model(), sim_->state());
  if (holding) {  // the hold goes on from the new static state: nothing left to ramp
    hold_start_time_ = sim_->state().time;
    for (int p : external_) hold_from_[p] = sim_->state().uplift[p];
  }
  diverged_ = false;
  recovering_ = false;
}

void HilNode::stop_worker() {
  {
    std::lock_guard<std::mutex> l(snap_mu_);
    stop_worker_ = true;
  }
  snap_cv_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void HilNode::reject(const std::string& what) {
  ++c_.rejected;
  ROS_ERROR_THROTTLE(1.0, "catenary_sim_hil: %s; measurement ignored, the previous one stays in effect (%lld rejected so "
                     "far)", what.c_str(), static_cast<long long>(c_.rejected));
}

void HilNode::on_measurement(const MeasuredContactForce::ConstPtr& msg) {
  const double arrival = steady_now();
  const std::size_t n = external_.size();
  if (msg->force.size() != n) {
    reject("hil/contact_force with " + std::to_string(msg->force.size()) + " values rejected: the scene has " +
           std::to_string(n) + " external pantograph(s), send one total force (N) each in scene order");
    return;
  }
  accept(msg->force.data(), arrival, msg->header.stamp, msg->step, "hil/contact_force.force", true);
}

void HilNode::on_wrench(const geometry_msgs::WrenchStamped::ConstPtr& msg) {
  const double arrival = steady_now();
  if (external_.size() != 1) {
    reject("hil/contact_wrench rejected: it carries one force (wrench.force.z) and the scene has " +
           std::to_string(external_.size()) + " external pantographs; send hil/contact_force with one total force each");
    return;
  }
  // Only force.z is used; a non-finite value anywhere is a broken reading.
  const geometry_msgs::Wrench& w = msg->wrench;
  const std::pair<const char*, double> others[] = {{"force.x", w.force.x},   {"force.y", w.force.y},
                                                   {"torque.x", w.torque.x}, {"torque.y", w.torque.y},
                                                   {"torque.z", w.torque.z}};
  for (const auto& o : others)
    if (!std::isfinite(o.second)) {
      reject(std::string("hil/contact_wrench.wrench.") + o.first + " = " + format_number(o.second) +
             " rejected: allowed a finite value (only force.z is used; the other components must be finite)");
      return;
    }
  const double f = w.force.z;
  accept(&f, arrival, msg->header.stamp, 0, "hil/contact_wrench.wrench.force.z", false);
}

bool HilNode::accept(const double* force, double arrival, const ros::Time& stamp_time, std::uint64_t step,
                     const char* field, bool indexed) {
  const std::size_t n = external_.size();
  // The core checks each value (NaN, inf, range); a rejected message changes nothing.
  std::string err;
  for (std::size_t i = 0; i < n; ++i) accept_buf_[i] = sim_->state().external_force[external_[i]];
  for (std::size_t i = 0; i < n; ++i) {
    if (!sim_->set_external_force(external_[i], force[i], &err)) {
      for (std::size_t j = 0; j < i; ++j) sim_->set_external_force(external_[j], accept_buf_[j], nullptr);
      reject(std::string(field) + (indexed ? "[" + std::to_string(i) + "]" : std::string()) + ": " + err);
      return false;
    }
  }
  for (std::size_t i = 0; i < n; ++i) accept_buf_[i] = sim_->state().external_force[external_[i]];
  const double stamp = stamp_time.toSec();
  if (stamp > 0.0) {
    const double transport = ros::WallTime::now().toSec() - stamp;
    if (transport >= 0.0 && transport < 1.0) transport_.add(transport);
  }
  if (unused_) ++c_.superseded;
  hold_.accept(accept_buf_, arrival, stamp, step);
  unused_ = true;
  ++c_.accepted;
  // Which period it starts. An answer to the last contact point published starts the next period
  // (a rig that sends no step is taken as answering the last one). An answer to an older one is
  // late: if the last period ran at its deadline without a measurement, this is the answer that
  // period lacked, so it is held but starts nothing (else it would take the next period and push
  // every later answer a period back); otherwise the rig is a period behind (its round trip is
  // longer than a period) and it starts the next period like any other.
  if (step == 0 || step >= published_step_) {
    fresh_ = true;
    owed_ = false;
  } else {
    ++c_.late;
    if (owed_) owed_ = false;
    else fresh_ = true;
  }
  return true;
}

void HilNode::wait_for_period(double w, double half, double& t) {
  // Wait for a fresh measurement inside the window [w - half, w + half], or for the window's end.
  // Blocking on the queue costs a wake-up (the thread that queued the measurement signals this
  // one); with ~hil/spin_wait the loop blocks only until that long before a due time (the start
  // of the window for an early measurement, else the expected arrival, the window's centre, on
  // which the windows are locked) and then polls the queue on the steady clock until it is (or,
  // for the arrival, until that long after it).
  const double spin = params_.spin_wait;
  auto running = [this] { return ros::ok() && !ros::isShuttingDown() && !stop_; };
  while (running()) {
    if (fresh_ && t >= w - half) break;
    if (t >= w + half) break;
    const double until = fresh_ ? w - half : w + half;
    double block_until = until;
    if (spin > 0.0) {
      const double due = fresh_ ? w - half : w;
      const double spin_end = fresh_ ? until : std::min(until, w + spin);
      if (t < due - spin) block_until = due - spin;
      else if (t < spin_end) block_until = t;  // poll
    }
    hil_queue_.callAvailable(ros::WallDuration(std::max(0.0, block_until - t)));
    t = steady_now();
  }
}

int HilNode::run() {
  prepare_loop_thread(params_.realtime_priority, "catenary_sim_hil");
  loop_running_ = true;
  const double period = timing_.period, half = 0.5 * period;
  publish_point();
  double w = steady_now() + period;  // centre of the next period's window
  const double start_wait_end = steady_now() + params_.start_delay;
  if (params_.start_delay > 0.0) ROS_INFO("catenary_sim_hil: measurements ignored for %g s (~start_delay)", params_.start_delay);
  next_snapshot_ = next_quantiles_ = steady_now();
  // (ros::ok() stays true while a shutdown closes the connections: without the second test the
  // rig's measurements would seem to stop and the loop enter the safe hold on its way out)
  auto running = [this] { return ros::ok() && !ros::isShuttingDown() && !stop_; };
  bool relock = false;  // centre the windows on the next arrival
  int off_centre = 0;   // triggering arrivals in a row more than a quarter period off the centre
  while (running() && !exit_requested_) {
    double t = steady_now();
    wait_for_period(w, half, t);
    if (!running()) break;
    poll_control();
    if (mode_ == Mode::kWaiting && (t < start_wait_end || !armed_)) fresh_ = false;  // (~start_delay, ~arm)
    const bool triggered = fresh_;
    if (mode_ == Mode::kWaiting && triggered) {
      w = t;  // the schedule starts on the rig's first measurement
      if (started_ == 0.0) started_ = t;
      relock = false;
      ROS_INFO("catenary_sim_hil: pass %u: first measurement received: running", pass_count_);
    } else if (triggered && relock) {
      w = std::max(t, w - half);  // centre the windows on this arrival (never earlier than this window)
      relock = false;
      ++c_.relocks;
    }
    batch(t, triggered);
    // Phase lock on the arrival of the measurement (not on the start of the steps, which waits for
    // the window of an early one). Arrivals far off the centre for many periods in a row (the
    // rig's phase changed) make the next one the centre at once.
    if (triggered) {
      const double offset = hold_.arrival() - w;
      off_centre = std::fabs(offset) > 0.25 * period ? off_centre + 1 : 0;
      if (off_centre >= kRelockPeriods) {
        relock = true;
        off_centre = 0;
      }
      w += period + std::clamp(kLockGain * offset, -kLockMax * period, kLockMax * period);
    } else {
      w += period;
    }
    const double done = steady_now();
    if (done >= next_snapshot_) snapshot(done);
    if (done > w + half) {
      // The next window closed before its steps could begin: the loop fell behind. Drop the
      // missed periods (dt is never stretched; simulation time falls behind the wall clock) but
      // keep the windows' phase, which is locked onto the rig.
      ++c_.overruns;
      const double missed = std::ceil((done - (w + half)) / period);
      ROS_WARN_THROTTLE(5.0, "catenary_sim_hil: overrun: the loop is %.3f ms behind its %g Hz schedule (%lld overruns "
                        "so far); %g period(s) dropped", (done - w) * 1e3, params_.rate,
                        static_cast<long long>(c_.overruns), missed);
      w += missed * period;
      relock = true;  // the windows' phase relative to the rig is lost: the next arrival sets it
    }
  }
  {
    std::lock_guard<std::mutex> l(ctrl_mu_);
    loop_running_ = false;  // (a waiting service answers at once)
  }
  ctrl_cv_.notify_all();
  // The statistics of a pass that has just ended are written before the exit code is decided.
  stop_worker();
  const bool report_ok = write_report();
  if ((!report_ok || stats_failed_) && exit_code_ == 0) exit_code_ = 1;
  return exit_code_;
}

void HilNode::enter_hold(double t, double age) {
  mode_ = Mode::kHold;
  ++c_.holds;
  hold_start_time_ = sim_->state().time;
  for (int p : external_) hold_from_[p] = sim_->state().external_force[p];
  std::string err;
  sim_->set_target_speed(0.0, &err);
  ROS_ERROR("catenary_sim_hil: no valid hil/contact_force for %.3f s (> ~hil/timeout = %g s): safe hold: the train "
            "stops (%g m/s^2) and the applied force ramps to the static uplift over %g s",
            std::isfinite(age) ? age : (t - started_), params_.timeout, params_.hold_deceleration, params_.hold_ramp);
}

void HilNode::leave_hold() {
  mode_ = Mode::kRunning;
  recovering_ = true;
  std::string err;
  sim_->set_target_speed(commanded_speed_, &err);
  ROS_WARN("catenary_sim_hil: fresh hil/contact_force: safe hold ended after %.3f s of simulation; the train "
           "accelerates back to %.1f km/h", sim_->state().time - hold_start_time_, commanded_speed_ * 3.6);
}

void HilNode::batch(double t, bool triggered) {
  if (mode_ == Mode::kEnded || mode_ == Mode::kPaused || (mode_ == Mode::kWaiting && !triggered)) {
    // (a measurement while waiting starts the run; paused or after the end it changes nothing, but
    // it is held: a pass resumed with the rig still sending is not in the safe hold)
    fresh_ = unused_ = false;
    publish_point();
    return;
  }
  if (mode_ == Mode::kWaiting) mode_ = Mode::kRunning;
  const double age = hold_.age(t);
  if (mode_ == Mode::kRunning && age > params_.timeout) enter_hold(t, age);
  else if (mode_ == Mode::kHold && triggered && !stopping_) leave_hold();
  ++c_.batches;
  if (triggered) ++c_.triggered;
  if (mode_ == Mode::kHold) ++c_.hold_batches;
  else if (!triggered) ++c_.held;
  if (mode_ == Mode::kRunning) c_.max_age_running = std::max(c_.max_age_running, age);
  age_in_effect_ = std::isfinite(age) ? age : -1.0;
  step_in_effect_ = mode_ == Mode::kRunning ? hold_.step() : 0;

  const Model& m = sim_->model();
  std::string err;
  for (int j = 0; j < timing_.steps_per_period; ++j) {
    const State& s = sim_->state();
    for (std::size_t i = 0; i < external_.size(); ++i) {
      const int p = external_[i];
      double f;
      if (mode_ == Mode::kHold) {
        const double static_force = s.uplift[p] + m.pantographs[p].aero_coefficient * s.speed * s.speed;
        f = hold_ramp_force(hold_from_[p], static_force, s.time - hold_start_time_, params_.hold_ramp);
      } else {
        f = hold_.value(i, t + j * timing_.dt, params_.extrapolate, params_.timeout);
      }
      f = std::clamp(f, 0.0, Simulation::kMaxExternalForce);
      sim_->set_external_force(p, f, &err);  // (finite and in range: cannot fail)
    }
    if (sim_->finished() || sim_->step() != StepStatus::kOk) break;
    // (the pass statistics leave the safe hold out: the train stands, and the recording would
    // grow for as long as the hold lasts)
    if (mode_ != Mode::kHold) recorder_->record(m, sim_->state());
  }
  if (recovering_ && sim_->state().speed >= sim_->state().target_speed - 1e-9) recovering_ = false;
  publish_point();
  const double published = steady_now();
  compute_.add(published - t);
  if (published - t > timing_.period)
    ROS_WARN_THROTTLE(5.0, "catenary_sim_hil: a period's steps and contact point took %.3f ms (period %g ms) at t = "
                      "%.4f s", (published - t) * 1e3, timing_.period * 1e3, sim_->state().time);
  if (unused_) latency_.add(published - hold_.arrival());  // the first output computed with it
  unused_ = false;
  owed_ = !triggered && mode_ == Mode::kRunning;  // ran at the deadline: its measurement may still come
  if (triggered) {
    wait_.add(t - hold_.arrival());
  }
  fresh_ = false;
  if (published >= next_quantiles_) {
    next_quantiles_ = published + kQuantilePeriod;
    q_latency_[0] = latency_.quantile(0.5);
    q_latency_[1] = latency_.quantile(0.99);
    q_latency_[2] = latency_.max();
  }
  handle_end();
}

void HilNode::publish_point() {
  const Model& m = sim_->model();
  const State& s = sim_->state();
  // (a shared pointer: a subscriber in the same process, e.g. VirtualRigNodelet, gets it without a copy)
  // Stamped in wall time, as the rig stamps its measurements (the loop runs on the wall clock);
  // the simulation time is in simulation_time (docs/hil.md, "Stamps").
  const ros::WallTime wall = ros::WallTime::now();
  const boost::shared_ptr<ContactPointArray> msg = boost::make_shared<ContactPointArray>(to_contact_points(
      m, s, ros::Time(wall.sec, wall.nsec), params_.line_frame, timing_.steps_per_period, scratch_));
  if (mode_ == Mode::kPaused) {
    // The line is held: the point does not move (an actuator following path_velocity stays put).
    for (ContactPoint& c : msg->pantographs) {
      c.velocity = c.acceleration = c.path_velocity = 0.0;
      for (auto* v : {&c.wire_velocity, &c.wire_acceleration, &c.wire_path_velocity}) std::fill(v->begin(), v->end(), 0.0);
    }
  }
  if (stopping_) {
    point_motion_ = 0.0;
    for (const ContactPoint& c : msg->pantographs)
      point_motion_ = std::max({point_motion_, std::fabs(c.velocity), std::fabs(c.path_velocity)});
  }
  msg->mode = mode_code(mode_);
  msg->pass_count = pass_count_;
  msg->measurement_step = step_in_effect_;
  for (ContactPoint& c : msg->pantographs) c.measurement_age = age_in_effect_;
  if (!all_finite(*msg)) {
    ROS_ERROR_THROTTLE(1.0, "catenary_sim_hil: a contact point with a non-finite value was not published (t = %g s)", s.time);
    return;
  }
  published_step_ = msg->step;
  point_pub_.publish(msg);
}

void HilNode::handle_end() {
  const State& s = sim_->state();
  if (mode_ == Mode::kEnded) return;
  const bool diverged = s.status == StepStatus::kDiverged;
  const bool stopped = stopping_ && stop_settled();
  if (!diverged && !stopped && !sim_->finished()) return;
  // The pass is over: its statistics go to the worker thread (filtering takes milliseconds).
  {
    std::lock_guard<std::mutex> l(snap_mu_);
    finished_recorder_ = std::move(recorder_);
    finished_state_ = s;
  }
  snap_cv_.notify_all();
  recorder_ = std::make_unique<PassRecorder>(sim_->model(), kRecorderRowRate);
  if (diverged) {
    diverged_ = true;
    ROS_ERROR("catenary_sim_hil: %s", sim_->status_message().c_str());
  } else if (stopping_) {
    ROS_INFO("catenary_sim_hil: pass %u stopped (~stop) at t = %.4f s (train front at %.2f m), the line settled: "
             "ended; %lld periods, %lld overruns", pass_count_, s.time, s.front + s.line_offset,
             static_cast<long long>(c_.batches), static_cast<long long>(c_.overruns));
  } else {
    ROS_INFO("catenary_sim_hil: pass %u finished at t = %.4f s (train front at %.2f m): %lld periods, %lld overruns",
             pass_count_, s.time, s.front + s.line_offset, static_cast<long long>(c_.batches), static_cast<long long>(c_.overruns));
  }
  if (!diverged && !stopping_ && params_.at_end == AtEnd::kLoop) {
    // A new pass from the initial static state with the static force (no new static solve), the
    // clock running on; pass_count tells the rig to re-initialise.
    for (int p : external_) sim_->set_external_force(p, sim_->state().uplift[p], nullptr);
    sim_->reset(true);
    ++pass_count_;
    recorder_->record(sim_->model(), sim_->state());
    return;
  }
  mode_ = Mode::kEnded;
  stopping_ = false;
  if (params_.at_end == AtEnd::kExit) {
    exit_requested_ = true;
    exit_code_ = diverged ? 1 : 0;
  }
}

void HilNode::snapshot(double t) {
  next_snapshot_ = t + 1.0 / params_.publish_rate;
  std::unique_lock<std::mutex> l(snap_mu_, std::try_to_lock);
  if (!l.owns_lock()) return;  // the worker is busy: next time
  snap_.state = sim_->state();
  snap_.mode = mode_;
  snap_.counters = c_;
  snap_.age = hold_.has_value() ? hold_.age(t) : -1.0;
  snap_.age_in_effect = age_in_effect_;
  std::copy(q_latency_, q_latency_ + 3, snap_.latency);
  snap_.diverged = diverged_;
  snap_.pass_count = pass_count_;
  snap_.armed = armed_;
  snap_.stopping = stopping_;
  snap_.recovering = recovering_;
  snap_.commanded_speed = commanded_speed_;
  snap_new_ = true;
  l.unlock();
  snap_cv_.notify_all();
}

void HilNode::worker() {
  // Slow work at normal priority even when the loop thread was made real-time.
  sched_param sp{};
  pthread_setschedparam(pthread_self(), SCHED_OTHER, &sp);
  const Model& m = sim_->model();
  while (true) {
    std::unique_ptr<PassRecorder> finished;
    State finished_state;
    bool have = false;
    {
      std::unique_lock<std::mutex> l(snap_mu_);
      snap_cv_.wait_for(l, std::chrono::milliseconds(100),
                        [this] { return snap_new_ || stop_worker_ || finished_recorder_ != nullptr; });
      // (stopping: only the statistics of a pass that has ended are still written)
      if (stop_worker_ && !finished_recorder_) return;
      if (snap_new_ && !stop_worker_) {
        std::swap(wsnap_, snap_);
        snap_new_ = false;
        have = true;
      }
      if (finished_recorder_) {
        finished = std::move(finished_recorder_);
        finished_state = finished_state_;
      }
    }
    if (have) {
      const State& s = wsnap_.state;
      const ros::Time stamp = sim_stamp(s.time, stamp_offset_);
      contact_pub_.publish(to_contact_force(m, s, stamp, params_.line_frame));
      if (pantograph_pub_.getNumSubscribers() > 0) publish_pantograph_state(m, s, stamp);
      if (s.time > last_tf_time_) {
        tf_.sendTransform(to_transforms(m, s, stamp, params_.line_frame));
        last_tf_time_ = s.time;
      }
      const double now = steady_now();
      if (now >= next_shape_wall_ && shape_pub_.getNumSubscribers() > 0) {
        next_shape_wall_ = now + 1.0 / params_.shape_rate;
        shape_pub_.publish(to_wire_shape(m, s, params_.shape_resolution, stamp, params_.line_frame));
      }
      if (now >= next_marker_wall_ && marker_pub_.getNumSubscribers() > 0) {
        next_marker_wall_ = now + 1.0 / params_.marker_rate;
        MarkerOptions o;
        o.frame = params_.line_frame;
        marker_pub_.publish(to_markers(m, s, stamp, o));
        if (stamp != last_view_stamp_) {
          tf_.sendTransform(to_view_transform(s, stamp, params_.line_frame));
          last_view_stamp_ = stamp;
        }
      }
    }
    if (finished) {
      const std::vector<PantographStatistics> stats = finished->statistics(m);
      for (const PantographStatistics& st : stats) {
        ROS_INFO("catenary_sim_hil: %s: mean %.1f N, std %.1f N, max %.1f N, min %.1f N, contact loss %.2f %% "
                 "(%zu samples, filtered %.0f Hz)", st.name.c_str(), st.filtered.mean, st.filtered.std_dev,
                 st.filtered.max, st.filtered.min, st.contact_loss_percent, st.samples, m.scene.output.filter_cutoff);
      }
      if (!params_.stats_file.empty()) {
        // Whole or not at all (checked writable at start-up; a full disk is still possible).
        try {
          write_file_atomically(params_.stats_file,
                                statistics_json(m, finished_state, stats, RunInfo{-1.0, -1.0, wsnap_.counters.overruns}));
        } catch (const OutputError& e) {
          end_error(std::string("catenary_sim_hil: ~stats_file: ") + e.what());
          stats_failed_ = true;
        }
      }
    }
    updater_.update();
  }
}

void HilNode::publish_pantograph_state(const Model& m, const State& s, const ros::Time& stamp) {
  PantographStateArray msg = to_pantograph_state(m, s, stamp, params_.line_frame);
  // An external pantograph has no masses here (its head is the real one on the rig): its head
  // height is the height the rig is told to impose, that of the contact point (never the NaN of a
  // simulated moving force).
  const ContactPointArray points = to_contact_points(m, s, stamp, params_.line_frame, timing_.steps_per_period,
                                                     worker_scratch_);
  for (std::size_t i = 0; i < external_.size() && i < points.pantographs.size(); ++i)
    msg.pantographs[external_[i]].head_height = points.pantographs[i].height;
  pantograph_pub_.publish(msg);
}

void HilNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  const Snapshot& s = wsnap_;
  const Counters& c = s.counters;
  using diagnostic_msgs::DiagnosticStatus;
  char what[256];
  switch (s.mode) {
    case Mode::kWaiting:
      stat.summary(DiagnosticStatus::WARN, s.armed ? "waiting for the first measurement on hil/contact_force"
                                                   : "waiting for ~arm (~hil/auto_start false)");
      break;
    case Mode::kRunning:
      if (s.recovering)
        stat.summary(DiagnosticStatus::WARN, "running: the train accelerates back after a safe hold");
      else
        stat.summary(DiagnosticStatus::OK, "running");
      break;
    case Mode::kPaused:
      stat.summary(DiagnosticStatus::OK, "paused (~set_paused): the line is held");
      break;
    case Mode::kHold:
      if (s.stopping) {
        stat.summary(DiagnosticStatus::WARN, "stopping (~stop): safe hold, then ended once the line has settled");
        break;
      }
      std::snprintf(what, sizeof what,
                    "SAFE HOLD: no valid hil/contact_force for %.3f s (> ~hil/timeout = %g s); train stopping, force "
                    "ramped to the static uplift", s.age, params_.timeout);
      stat.summary(DiagnosticStatus::ERROR, what);
      break;
    case Mode::kEnded:
      if (s.diverged) stat.summary(DiagnosticStatus::ERROR, "diverged: the loop is stopped");
      else stat.summary(DiagnosticStatus::OK, "pass finished");
      break;
  }
  stat.add("mode", mode_name(s.mode));
  stat.add("measurement age [s]", s.age);
  stat.add("age of the measurement in effect [s]", s.age_in_effect);
  stat.add("max measurement age while running [s]", c.max_age_running);
  stat.add("timeout [s]", params_.timeout);
  stat.add("rate [Hz]", params_.rate);
  stat.add("dt [s]", sim_->model().dt);
  stat.add("steps per period", timing_.steps_per_period);
  stat.add("periods", c.batches);
  stat.add("periods started by a measurement", c.triggered);
  stat.add("periods with the held measurement", c.held);
  stat.add("periods in safe hold", c.hold_batches);
  stat.add("safe holds", c.holds);
  stat.add("overruns", c.overruns);
  stat.add("measurements accepted", c.accepted);
  stat.add("measurements rejected", c.rejected);
  stat.add("measurements superseded", c.superseded);
  stat.add("measurements late (answering an older contact point)", c.late);
  stat.add("latency p50 [s]", s.latency[0]);
  stat.add("latency p99 [s]", s.latency[1]);
  stat.add("latency max [s]", s.latency[2]);
  stat.add("sim time [s]", s.state.time);
  stat.add("steps", s.state.steps);
  stat.add("train front [m]", s.state.front + s.state.line_offset);
  stat.add("speed [m/s]", s.state.speed);
  stat.add("commanded speed [m/s]", s.commanded_speed);
  stat.add("pass", s.pass_count);
}

bool HilNode::write_report() const {
  const double wall = started_ > 0.0 ? steady_now() - started_ : 0.0;
  // (printf: after a shutdown rosconsole no longer prints)
  std::printf("catenary_sim_hil: %lld periods in %.1f s, %lld overruns, %lld safe holds; latency (measurement arrival "
              "-> contact point published) p50 %.1f us, p99 %.1f us, max %.1f us over %llu measurements\n",
              static_cast<long long>(c_.batches), wall, static_cast<long long>(c_.overruns),
              static_cast<long long>(c_.holds), latency_.quantile(0.5) * 1e6, latency_.quantile(0.99) * 1e6,
              latency_.max() * 1e6, static_cast<unsigned long long>(latency_.count()));
  std::fflush(stdout);
  if (params_.report_file.empty()) return true;
  // nlohmann::json writes a non-finite number as null.
  auto hist = [](const LatencyHistogram& h) {
    nlohmann::ordered_json j;
    j["count"] = h.count();
    j["mean_s"] = h.mean();
    j["p50_s"] = h.quantile(0.5);
    j["p90_s"] = h.quantile(0.9);
    j["p99_s"] = h.quantile(0.99);
    j["p999_s"] = h.quantile(0.999);
    j["max_s"] = h.max();
    return j;
  };
  nlohmann::ordered_json j;
  j["rate_hz"] = params_.rate;
  j["period_s"] = timing_.period;
  j["dt_s"] = sim_->model().dt;
  j["steps_per_period"] = timing_.steps_per_period;
  j["dofs"] = sim_->model().n_dof;
  j["wall_s"] = wall;
  j["sim_time_s"] = sim_->state().time;
  j["passes"] = pass_count_ + 1;
  j["periods"] = c_.batches;
  j["periods_triggered"] = c_.triggered;
  j["periods_held"] = c_.held;
  j["periods_safe_hold"] = c_.hold_batches;
  j["safe_holds"] = c_.holds;
  j["overruns"] = c_.overruns;
  j["relocks"] = c_.relocks;
  j["spin_wait_s"] = params_.spin_wait;
  j["measurements_accepted"] = c_.accepted;
  j["measurements_rejected"] = c_.rejected;
  j["measurements_superseded"] = c_.superseded;
  j["measurements_late"] = c_.late;
  j["max_age_running_s"] = c_.max_age_running;
  j["latency"] = hist(latency_);
  j["compute"] = hist(compute_);
  j["wait"] = hist(wait_);
  j["transport"] = hist(transport_);
  try {
    write_file_atomically(params_.report_file, j.dump(2) + "\n");
  } catch (const OutputError& e) {
    end_error(std::string("catenary_sim_hil: ~hil/report_file: ") + e.what());
    return false;
  }
  return true;
}

}  // namespace ros_layer
}  // namespace catenary_sim
