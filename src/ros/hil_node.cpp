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
#include "catenary_sim/core/output/output_files.hpp"
#include "catenary_sim/hil/report.hpp"
#include "catenary_sim/ros/conversions.hpp"
#include "catenary_sim/ros/markers.hpp"

namespace catenary_sim {
namespace ros_layer {

namespace {

using hil::steady_now;

// How long a service waits for the loop to take its request: a period is at most 1 ms, but on a
// loaded machine the loop can fall far behind; a request not taken in time is withdrawn.
constexpr double kControlWait = 5.0;  // s (wall)

// How long the pass waits after rviz has subscribed before it starts (its displays draw late).
constexpr double kViewerSettle = 1.0;  // s (wall)

// An error at the end of the run: after a shutdown rosconsole no longer prints, so then on stderr.
void end_error(const std::string& what) {
  if (ros::ok() && !ros::isShuttingDown()) ROS_ERROR("%s", what.c_str());
  else std::fprintf(stderr, "[ERROR] %s\n", what.c_str());
}

}  // namespace

HilNode::HilNode(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(nh), pnh_(pnh), params_(load_hil_params(pnh)), updater_(nh, pnh) {
  const Scene scene = load_hil_scene(params_);
  make_loop(scene);
  loop_->attach(this);
  external_ = loop_->external();
  stamp_offset_ = std::floor(ros::WallTime::now().toSec());
  advertise_outputs();
  subscribe_measurements();
  serve_control();
  updater_.setHardwareID("catenary_sim_hil/" + scene.name);
  updater_.add("hardware in the loop", this, &HilNode::diagnose);
  log_start(scene);
  worker_ = std::thread([this] { worker(); });
}

void HilNode::make_loop(const Scene& scene) {
  try {
    hil::LoopOptions o = loop_options(params_);
    // Waiting for the viewer: the pass is armed by the worker once rviz subscribes (or the wait is
    // over), so that its start is seen; until then the line holds its static state.
    if (params_.wait_for_viewer > 0.0 && params_.auto_start) {
      o.auto_start = false;
      viewer_wait_until_ = steady_now() + params_.wait_for_viewer;
    }
    o.who = "catenary_sim_hil";
    o.input = "hil/contact_force";
    loop_ = std::make_unique<hil::HilLoop>(scene, o);
  } catch (const SceneError& e) {
    throw ParamError("parameter ~scene = '" + params_.scene + "': " + e.what());
  } catch (const hil::HilError& e) {
    throw ParamError(e.what());
  }
}

void HilNode::advertise_outputs() {
  // One second of contact points queued per subscriber: a subscriber stalled for a few periods (a
  // loaded machine) gets them late instead of losing them; roscpp drops the oldest of a fuller
  // queue, and a rig that loses one integrates its pantograph against an extrapolated wire for
  // two periods, a recorder a hole in its series (test_ros_hil_loop at 2 kHz on a loaded 2-core
  // machine lost 41 in a pass with a queue of 10).
  point_pub_ = nh_.advertise<ContactPointArray>("hil/contact_point", static_cast<std::uint32_t>(std::ceil(params_.rate)));
  contact_pub_ = nh_.advertise<ContactForceArray>("contact_force", 10);
  pantograph_pub_ = nh_.advertise<PantographStateArray>("pantograph_state", 10);
  shape_pub_ = nh_.advertise<WireShapeArray>("wire_shape", 2);
  marker_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("markers", 2);
}

void HilNode::subscribe_measurements() {
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
}

void HilNode::serve_control() {
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
}

void HilNode::log_start(const Scene& scene) const {
  const Model& m = loop_->model();
  const hil::HilTiming& timing = loop_->timing();
  std::string names;
  for (int p : external_) names += (names.empty() ? "" : ", ") + m.pantographs[p].name;
  ROS_INFO("catenary_sim_hil: scene %s: %d DOFs, external pantograph(s) %s; loop %g Hz (period %g ms) = %d step(s) "
           "of dt %.6g ms (stability limit %.4g ms); speed %.1f km/h; timeout %g s; %s; at_end %s",
           scene.name.c_str(), m.n_dof, names.c_str(), params_.rate, timing.period * 1e3, timing.steps_per_period,
           m.dt * 1e3, m.dt_critical * 1e3, scene.train_speed * 3.6, params_.timeout,
           params_.extrapolate ? "linear extrapolation" : "newest measurement held", to_string(params_.at_end));
  if (viewer_wait_until_ > 0.0)
    ROS_INFO("catenary_sim_hil: waiting up to %g s for a viewer (rviz) to subscribe to %s (~wait_for_viewer); the "
             "pass then starts with the first measurement", params_.wait_for_viewer, marker_pub_.getTopic().c_str());
  else if (params_.auto_start)
    ROS_INFO("catenary_sim_hil: waiting for the first measurement on %s%s (the line holds its static state)",
             force_sub_.getTopic().c_str(),
             external_.size() == 1 ? (" or " + wrench_sub_.getTopic()).c_str() : "");
  else
    ROS_INFO("catenary_sim_hil: ~hil/auto_start false: the line holds its static state until `rosservice call %s`; "
             "the pass then starts with the first measurement", arm_srv_.getService().c_str());
}

HilNode::~HilNode() {
  if (ctrl_spinner_) ctrl_spinner_->stop();  // (before the services and their queue go)
  stop_worker();
}

// ---- hil::LoopSkin ----

void HilNode::log(hil::LogLevel level, const std::string& text) {
  switch (level) {
    case hil::LogLevel::kInfo: ROS_INFO("%s", text.c_str()); break;
    case hil::LogLevel::kWarn: ROS_WARN("%s", text.c_str()); break;
    case hil::LogLevel::kError: ROS_ERROR("%s", text.c_str()); break;
  }
}

void HilNode::receive(double until) {
  hil_queue_.callAvailable(ros::WallDuration(std::max(0.0, until - steady_now())));
}

void HilNode::send(const hil::PointFrame& frame) {
  // (a shared pointer: a subscriber in the same process, e.g. VirtualRigNodelet, gets it without a copy)
  // Stamped in wall time, as the rig stamps its measurements (the loop runs on the wall clock);
  // the simulation time is in simulation_time (docs/hil.md, "Stamps").
  const ros::WallTime wall = ros::WallTime::now();
  const boost::shared_ptr<ContactPointArray> msg = boost::make_shared<ContactPointArray>(
      to_contact_points(loop_->model(), frame, ros::Time(wall.sec, wall.nsec), params_.line_frame));
  if (!all_finite(*msg)) return;  // (the frame was checked: only the stamp could be)
  point_pub_.publish(msg);
}

void HilNode::after_period(double now) {
  if (now >= next_snapshot_) snapshot(now);
}

void HilNode::pass_ended(std::unique_ptr<PassRecorder> recorder, const State& state) {
  // Its statistics go to the worker thread (filtering takes milliseconds).
  {
    std::lock_guard<std::mutex> l(snap_mu_);
    finished_recorder_ = std::move(recorder);
    finished_state_ = state;
  }
  snap_cv_.notify_all();
}

// ---- Control: services and commands (control thread) ----

void HilNode::on_speed(const std_msgs::Float64::ConstPtr& msg) {
  const double v = msg->data;
  if (const std::string e = speed_command_error(loop_->model().scene, v); !e.empty()) {
    ROS_ERROR_THROTTLE(1.0, "catenary_sim_hil: %s; command ignored", e.c_str());
    return;
  }
  if (const std::string w = speed_warning(loop_->model(), v); !w.empty())  // (the model is never changed)
    ROS_WARN_THROTTLE(5.0, "catenary_sim_hil: %s", w.c_str());
  loop_->command_speed(v);
}

std::pair<bool, std::string> HilNode::ask_loop(Request r, const char* service) {
  const std::pair<bool, std::string> answer = loop_->ask(r, kControlWait);
  if (answer.first) ROS_INFO("catenary_sim_hil: ~%s: %s", service, answer.second.c_str());
  else ROS_WARN("catenary_sim_hil: ~%s: %s", service, answer.second.c_str());
  return answer;
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

void HilNode::stop_worker() {
  {
    std::lock_guard<std::mutex> l(snap_mu_);
    stop_worker_ = true;
  }
  snap_cv_.notify_all();
  if (worker_.joinable()) worker_.join();
}

// ---- Measurements (loop thread, from receive) ----

void HilNode::on_measurement(const MeasuredContactForce::ConstPtr& msg) {
  const double arrival = steady_now();
  const double stamp = msg->header.stamp.toSec();
  if (loop_->accept(msg->force.data(), msg->force.size(), arrival, stamp, msg->step, "hil/contact_force.force", true) &&
      stamp > 0.0) {
    const double transport = ros::WallTime::now().toSec() - stamp;
    if (transport >= 0.0 && transport < 1.0) loop_->add_transport(transport);
  }
}

void HilNode::on_wrench(const geometry_msgs::WrenchStamped::ConstPtr& msg) {
  const double arrival = steady_now();
  if (external_.size() != 1) {
    loop_->reject("hil/contact_wrench rejected: it carries one force (wrench.force.z) and the scene has " +
                  std::to_string(external_.size()) +
                  " external pantographs; send hil/contact_force with one total force each");
    return;
  }
  // Only force.z is used; a non-finite value anywhere is a broken reading.
  const geometry_msgs::Wrench& w = msg->wrench;
  const std::pair<const char*, double> others[] = {{"force.x", w.force.x},   {"force.y", w.force.y},
                                                   {"torque.x", w.torque.x}, {"torque.y", w.torque.y},
                                                   {"torque.z", w.torque.z}};
  for (const auto& o : others)
    if (!std::isfinite(o.second)) {
      loop_->reject(std::string("hil/contact_wrench.wrench.") + o.first + " = " + format_given(o.second) +
                    " rejected: allowed a finite value (only force.z is used; the other components must be finite)");
      return;
    }
  const double f = w.force.z;
  const double stamp = msg->header.stamp.toSec();
  if (loop_->accept(&f, 1, arrival, stamp, 0, "hil/contact_wrench.wrench.force.z", false) && stamp > 0.0) {
    const double transport = ros::WallTime::now().toSec() - stamp;
    if (transport >= 0.0 && transport < 1.0) loop_->add_transport(transport);
  }
}

int HilNode::run() {
  // Real time (~hil/realtime_priority, ~hil/lock_memory, ~hil/cpus): a refusal is an error naming
  // the parameter, and the node does not run (a rig needs to know its loop is not what it asked).
  if (const std::string e = hil::apply_realtime(realtime_options(params_)); !e.empty()) {
    ROS_FATAL("catenary_sim_hil: parameter %s", e.c_str());
    stop_worker();
    return 2;
  }
  if (params_.realtime_priority > 0 || !params_.cpus.empty())
    ROS_INFO("catenary_sim_hil: loop thread%s%s%s", params_.realtime_priority > 0 ? " at SCHED_FIFO priority " : "",
             params_.realtime_priority > 0 ? std::to_string(params_.realtime_priority).c_str() : "",
             params_.cpus.empty() ? "" : (" on CPU(s) " + params_.cpus).c_str());
  next_snapshot_ = steady_now();
  int exit_code = loop_->run();
  // The statistics of a pass that has just ended are written before the exit code is decided.
  stop_worker();
  const bool report_ok = write_report();
  if ((!report_ok || stats_failed_) && exit_code == 0) exit_code = 1;
  return exit_code;
}

void HilNode::snapshot(double t) {
  next_snapshot_ = t + 1.0 / params_.publish_rate;
  std::unique_lock<std::mutex> l(snap_mu_, std::try_to_lock);
  if (!l.owns_lock()) return;  // the worker is busy: next time
  const hil::HilLoop& L = *loop_;
  snap_.state = L.state();
  snap_.mode = L.mode();
  snap_.counters = L.counters();
  snap_.age = L.age(t);
  snap_.age_in_effect = L.age_in_effect();
  std::copy(L.latency_quantiles(), L.latency_quantiles() + 3, snap_.latency);
  snap_.jitter = L.jitter_summary();
  snap_.diverged = L.diverged();
  snap_.dewired = L.dewired();
  snap_.pass_count = L.pass_count();
  snap_.armed = L.armed();
  snap_.stopping = L.stopping();
  snap_.recovering = L.recovering();
  snap_.commanded_speed = L.commanded_speed();
  snap_new_ = true;
  l.unlock();
  snap_cv_.notify_all();
}

void HilNode::worker() {
  // Slow work at normal priority even when the loop thread was made real-time.
  sched_param sp{};
  pthread_setschedparam(pthread_self(), SCHED_OTHER, &sp);
  const Model& m = loop_->model();
  while (true) {
    std::unique_ptr<PassRecorder> finished;
    State finished_state;
    bool have = false;
    if (!take_work(&have, &finished, &finished_state)) return;
    if (viewer_wait_until_ > 0.0) arm_when_viewer_ready();
    if (have) publish_snapshot(m);
    if (finished) report_pass(m, *finished, finished_state);
    updater_.update();
  }
}

bool HilNode::take_work(bool* have, std::unique_ptr<PassRecorder>* finished, State* finished_state) {
  std::unique_lock<std::mutex> l(snap_mu_);
  snap_cv_.wait_for(l, std::chrono::milliseconds(100),
                    [this] { return snap_new_ || stop_worker_ || finished_recorder_ != nullptr; });
  // (stopping: only the statistics of a pass that has ended are still written)
  if (stop_worker_ && !finished_recorder_) return false;
  if (snap_new_ && !stop_worker_) {
    std::swap(wsnap_, snap_);
    snap_new_ = false;
    *have = true;
  }
  if (finished_recorder_) {
    *finished = std::move(finished_recorder_);
    *finished_state = finished_state_;
  }
  return true;
}

void HilNode::publish_snapshot(const Model& m) {
  const State& s = wsnap_.state;
  const ros::Time stamp = sim_stamp(s.time, stamp_offset_);
  // The chart's samples on simulated time; a new pass (or a reset) starts a new chart.
  if (params_.strip_chart) {
    if (wsnap_.pass_count != chart_pass_ || (!chart_.empty() && s.time < chart_time_)) {
      chart_.clear(params_.chart_window);
      chart_pass_ = wsnap_.pass_count;
    }
    if (chart_.due(s.time, 1e-3 * params_.chart_window)) chart_.sample(m, s);
    chart_time_ = s.time;
  }
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
    visualization_msgs::MarkerArray arr = to_markers(m, s, stamp, o);
    if (params_.strip_chart) {
      // The heads-up line (the loop's mode instead of a real-time factor: the loop runs on the
      // wall clock) and the statistics so far, in the chart's panel, which follows the train.
      const visualization_msgs::MarkerArray chart = chart_.markers(
          m, heads_up_position(m, s) + "  hardware in the loop: " + hil::mode_name(wsnap_.mode), stamp);
      arr.markers.insert(arr.markers.end(), chart.markers.begin(), chart.markers.end());
    }
    marker_pub_.publish(arr);
    if (stamp != last_view_stamp_) {
      tf_.sendTransform(to_view_transform(s, stamp, params_.line_frame));
      last_view_stamp_ = stamp;
    }
  }
}

void HilNode::report_pass(const Model& m, const PassRecorder& finished, const State& finished_state) {
  const std::vector<PantographStatistics> stats = finished.statistics(m);
  std::string why;
  const std::string text =
      hil::pass_stats_json(m, finished_state, stats, RunInfo{-1.0, -1.0, wsnap_.counters.overruns}, &why);
  if (text.empty()) {
    // (a pass with no statistics: the file asked for is missing, which the exit code says)
    end_error("catenary_sim_hil: " + why);
    if (!params_.stats_file.empty()) stats_failed_ = true;
    return;
  }
  for (const PantographStatistics& st : stats) {
    ROS_INFO("catenary_sim_hil: %s: mean %.1f N, std %.1f N, max %.1f N, min %.1f N, contact loss %.2f %% "
             "(%zu samples, filtered %.0f Hz)", st.name.c_str(), st.filtered.mean, st.filtered.std_dev,
             st.filtered.max, st.filtered.min, st.contact_loss_percent, st.samples, m.scene.output.filter_cutoff);
  }
  if (!params_.stats_file.empty()) {
    // Whole or not at all (checked writable at start-up; a full disk is still possible).
    try {
      write_file_atomically(params_.stats_file, text);
    } catch (const OutputError& e) {
      end_error(std::string("catenary_sim_hil: ~stats_file: ") + e.what());
      stats_failed_ = true;
    }
  }
}

void HilNode::arm_when_viewer_ready() {
  const double now = steady_now();
  if (viewer_seen_ < 0.0 && marker_pub_.getNumSubscribers() > 0) {
    // rviz subscribes before its displays have drawn the first frame: give it a moment.
    viewer_seen_ = now;
    viewer_wait_until_ = std::min(viewer_wait_until_, now + kViewerSettle);
  }
  if (now < viewer_wait_until_) return;
  if (viewer_seen_ < 0.0)
    ROS_WARN("catenary_sim_hil: no viewer subscribed within %g s; starting anyway", params_.wait_for_viewer);
  viewer_wait_until_ = 0.0;
  ask_loop(Request::kArm, "wait_for_viewer");
}

void HilNode::publish_pantograph_state(const Model& m, const State& s, const ros::Time& stamp) {
  PantographStateArray msg = to_pantograph_state(m, s, stamp, params_.line_frame);
  // An external pantograph has no masses here (its head is the real one on the rig): its head
  // height is the height the rig is told to impose, that of the contact point (never the NaN of a
  // simulated moving force).
  const ContactPointArray points = to_contact_points(m, s, stamp, params_.line_frame, loop_->timing().steps_per_period,
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
      else if (s.dewired) stat.summary(DiagnosticStatus::ERROR, "stopped at a dewirement (pantograph_head.on_dewirement: stop)");
      else stat.summary(DiagnosticStatus::OK, "pass finished");
      break;
  }
  stat.add("mode", hil::mode_name(s.mode));
  stat.add("measurement age [s]", s.age);
  stat.add("age of the measurement in effect [s]", s.age_in_effect);
  stat.add("max measurement age while running [s]", c.max_age_running);
  stat.add("timeout [s]", params_.timeout);
  stat.add("rate [Hz]", params_.rate);
  stat.add("dt [s]", loop_->model().dt);
  stat.add("steps per period", loop_->timing().steps_per_period);
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
  // The loop's jitter: how late each period started after its due time (docs/hil.md, "A rig PC").
  stat.add("jitter p50 [s]", s.jitter.p50);
  stat.add("jitter p99 [s]", s.jitter.p99);
  stat.add("jitter max [s]", s.jitter.max);
  for (std::size_t i = 0; i < s.jitter.counts.size(); ++i)
    stat.add(std::string("jitter ") + hil::JitterSummary::kLabels[i] + " [periods]", s.jitter.counts[i]);
  stat.add("sim time [s]", s.state.time);
  stat.add("steps", s.state.steps);
  stat.add("train front [m]", s.state.front + s.state.line_offset);
  stat.add("speed [m/s]", s.state.speed);
  stat.add("commanded speed [m/s]", s.commanded_speed);
  stat.add("pass", s.pass_count);
}

bool HilNode::write_report() const {
  // (printf: after a shutdown rosconsole no longer prints)
  std::printf("catenary_sim_hil: %s\n", hil::loop_summary(*loop_).c_str());
  std::fflush(stdout);
  if (params_.report_file.empty()) return true;
  try {
    write_file_atomically(params_.report_file, hil::loop_report(*loop_).dump(2) + "\n");
  } catch (const OutputError& e) {
    end_error(std::string("catenary_sim_hil: ~hil/report_file: ") + e.what());
    return false;
  }
  return true;
}

}  // namespace ros_layer
}  // namespace catenary_sim
