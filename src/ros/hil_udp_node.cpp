#include "catenary_sim/ros/hil_udp_node.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>

#include "catenary_sim/ContactPointArray.h"
#include "catenary_sim/core/output/output_files.hpp"
#include "catenary_sim/hil/report.hpp"
#include "catenary_sim/ros/conversions.hpp"
#include "catenary_sim/ros/params.hpp"

namespace catenary_sim {
namespace ros_layer {

namespace {
constexpr double kControlWait = 5.0;  // s, as catenary_sim_hil_node
}

HilUdpNode::HilUdpNode(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(nh), pnh_(pnh), params_(load_hil_params(pnh)), updater_(nh, pnh) {
  const Scene scene = load_hil_scene(params_);
  hil::LoopOptions o = loop_options(params_);
  o.who = "catenary_sim_hil_udp";
  o.input = "UDP measurement";
  hil::UdpLoopOptions u;
  u.bind_address = params_.udp_bind;
  u.port = params_.udp_port;
  u.bind_name = "~hil/udp_bind/~hil/udp_port";
  u.rig_name = "~hil/udp_rig";
  u.allow_name = "~hil/udp_allow";
  u.scene_name = "~scene = '" + params_.scene + "'";
  try {
    if (!params_.udp_rig.empty()) std::tie(u.rig_address, u.rig_port) = hil::parse_host_port(params_.udp_rig, "~hil/udp_rig");
    u.allow = hil::parse_allow_list(params_.udp_allow, "~hil/udp_allow");
  } catch (const hil::HilError& e) {
    throw ParamError(std::string("parameter ") + e.what());
  }
  try {
    loop_ = std::make_unique<hil::HilLoop>(scene, o);
  } catch (const SceneError& e) {
    throw ParamError("parameter ~scene = '" + params_.scene + "': " + e.what());
  } catch (const hil::HilError& e) {
    throw ParamError(e.what());  // (the loop's errors name their parameter, as catenary_sim_hil_node's)
  }
  try {
    skin_ = std::make_unique<hil::UdpLoopSkin>(*loop_, u, &ring_);
  } catch (const hil::HilError& e) {
    throw ParamError(std::string("parameter ") + e.what());  // (named by UdpLoopOptions' names)
  }
  skin_->set_running([] { return ros::ok() && !ros::isShuttingDown(); });
  skin_->set_on_pass_ended([this](std::unique_ptr<PassRecorder> recorder, const State& state) {
    std::lock_guard<std::mutex> l(pass_mu_);  // (the publisher holds it only to take the recorder)
    pass_recorder_ = std::move(recorder);
    pass_state_ = state;
    pass_overruns_ = loop_->counters().overruns;
  });
  skin_->set_log([](hil::LogLevel level, const std::string& t) {
    if (level == hil::LogLevel::kInfo) ROS_INFO("%s", t.c_str());
    else if (level == hil::LogLevel::kWarn) ROS_WARN("%s", t.c_str());
    else ROS_ERROR("%s", t.c_str());
  });
  wall_offset_ = ros::WallTime::now().toSec() - hil::steady_now();
  point_pub_ = nh_.advertise<ContactPointArray>("hil/contact_point", static_cast<std::uint32_t>(std::ceil(params_.rate)));
  auto trigger = [this](const char* name, hil::Request r) {
    ros::AdvertiseServiceOptions so = ros::AdvertiseServiceOptions::create<std_srvs::Trigger>(
        name,
        [this, r, name](std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
          std::tie(res.success, res.message) = ask(r, name);
          return true;
        },
        ros::VoidConstPtr(), &ctrl_queue_);
    return pnh_.advertiseService(so);
  };
  arm_srv_ = trigger("arm", hil::Request::kArm);
  reset_srv_ = trigger("reset", hil::Request::kReset);
  stop_srv_ = trigger("stop", hil::Request::kStop);
  ros::AdvertiseServiceOptions po = ros::AdvertiseServiceOptions::create<std_srvs::SetBool>(
      "set_paused",
      [this](std_srvs::SetBool::Request& q, std_srvs::SetBool::Response& res) {
        std::tie(res.success, res.message) = ask(q.data ? hil::Request::kPause : hil::Request::kResume, "set_paused");
        return true;
      },
      ros::VoidConstPtr(), &ctrl_queue_);
  pause_srv_ = pnh_.advertiseService(po);
  ros::SubscribeOptions vo = ros::SubscribeOptions::create<std_msgs::Float64>(
      "cmd/train_speed", 10,
      [this](const std_msgs::Float64::ConstPtr& msg) {
        if (const std::string e = speed_command_error(loop_->model().scene, msg->data); !e.empty()) {
          ROS_ERROR_THROTTLE(1.0, "catenary_sim_hil_udp: %s; command ignored", e.c_str());
          return;
        }
        loop_->command_speed(msg->data);
      },
      ros::VoidPtr(), &ctrl_queue_);
  speed_sub_ = nh_.subscribe(vo);
  ctrl_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &ctrl_queue_);
  ctrl_spinner_->start();
  updater_.setHardwareID("catenary_sim_hil_udp/" + scene.name);
  updater_.add("hardware in the loop (UDP)", this, &HilUdpNode::diagnose);
  ROS_INFO("catenary_sim_hil_udp: scene %s: loop %g Hz = %d step(s) of %.6g ms; rig over UDP on %s:%d%s",
           scene.name.c_str(), params_.rate, loop_->timing().steps_per_period, loop_->model().dt * 1e3,
           params_.udp_bind.c_str(), skin_->port(),
           params_.udp_rig.empty() ? "" : (", sending to " + params_.udp_rig).c_str());
  publisher_ = std::thread([this] { publisher(); });
}

HilUdpNode::~HilUdpNode() {
  if (ctrl_spinner_) ctrl_spinner_->stop();
  stop_publisher_ = true;
  if (publisher_.joinable()) publisher_.join();
}

std::pair<bool, std::string> HilUdpNode::ask(hil::Request r, const char* service) {
  const auto answer = loop_->ask(r, kControlWait);
  if (answer.first) ROS_INFO("catenary_sim_hil_udp: ~%s: %s", service, answer.second.c_str());
  else ROS_WARN("catenary_sim_hil_udp: ~%s: %s", service, answer.second.c_str());
  return answer;
}

void HilUdpNode::publisher() {
  // Normal scheduling whatever the loop thread gets; drains the ring every millisecond.
  hil::MonitorSample s;
  double next_diag = 0.0;
  while (!stop_publisher_) {
    bool any = false;
    while (ring_.pop(s)) {
      any = true;
      last_ = s;
      ++published_;
      if (point_pub_.getNumSubscribers() == 0) continue;
      const boost::shared_ptr<ContactPointArray> m = boost::make_shared<ContactPointArray>();
      m->header.stamp.fromSec(s.wall + wall_offset_);  // (wall time of sending, as the TCPROS node's)
      m->header.frame_id = params_.line_frame;
      m->simulation_time = s.simulation_time;
      m->step = s.step;
      m->pass_count = s.pass_count;
      m->dt = loop_->model().dt;  // (constant)
      m->steps_per_period = static_cast<std::uint32_t>(loop_->timing().steps_per_period);
      m->speed = s.speed;
      m->mode = s.mode;
      m->measurement_step = s.measurement_step;
      for (std::uint32_t i = 0; i < s.pantographs; ++i) {
        ContactPoint c;
        c.name = loop_->model().pantographs[loop_->external()[i]].name;
        c.position = s.position[i];
        c.height = s.height[i];
        c.velocity = s.velocity[i];
        c.path_velocity = s.path_velocity[i];
        c.applied_force = s.applied_force[i];
        c.measurement_age = s.measurement_age[i];
        m->pantographs.push_back(std::move(c));
      }
      point_pub_.publish(m);
    }
    report_finished_pass();
    const double now = hil::steady_now();
    if (now >= next_diag) {
      next_diag = now + 0.1;
      updater_.update();  // (at its own ~diagnostic_period)
    }
    if (!any) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

void HilUdpNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  using diagnostic_msgs::DiagnosticStatus;
  const hil::MonitorSample& s = last_;
  const hil::Mode mode = static_cast<hil::Mode>(s.mode);
  if (mode == hil::Mode::kHold) stat.summary(DiagnosticStatus::ERROR, "SAFE HOLD: no valid UDP measurement within ~hil/timeout");
  else if (mode == hil::Mode::kWaiting) stat.summary(DiagnosticStatus::WARN, "waiting for the first UDP measurement");
  else stat.summary(DiagnosticStatus::OK, hil::mode_name(mode));
  stat.add("mode", hil::mode_name(mode));
  stat.add("periods", s.periods);
  stat.add("overruns", s.overruns);
  stat.add("periods with the held measurement", s.held);
  stat.add("safe holds", s.holds);
  stat.add("measurements rejected", s.rejected);
  stat.add("packets lost", s.packets_lost);
  stat.add("packets reordered", s.packets_reordered);
  stat.add("packets duplicated", s.packets_duplicated);
  stat.add("packets from other senders", s.packets_foreign);
  stat.add("packets refused (~hil/udp_allow)", s.packets_refused);
  stat.add("latency p99 [s]", s.latency_p99);
  stat.add("jitter p50 [s]", s.jitter_p50);
  stat.add("jitter p99 [s]", s.jitter_p99);
  stat.add("jitter max [s]", s.jitter_max);
  for (std::size_t i = 0; i < s.jitter_counts.size(); ++i)
    stat.add(std::string("jitter ") + hil::JitterSummary::kLabels[i] + " [periods]", s.jitter_counts[i]);
  stat.add("delay energy [J]", s.delay_energy);
  stat.add("monitor dropped", ring_.dropped());
  stat.add("sim time [s]", s.simulation_time);
}

void HilUdpNode::report_finished_pass() {
  std::unique_ptr<PassRecorder> rec;
  State state;
  std::int64_t overruns = 0;
  {
    std::lock_guard<std::mutex> l(pass_mu_);
    if (!pass_recorder_) return;
    rec = std::move(pass_recorder_);
    state = pass_state_;
    overruns = pass_overruns_;
  }
  // An error after a shutdown on stderr (rosconsole no longer prints then).
  auto error = [](const std::string& what) {
    if (ros::ok() && !ros::isShuttingDown()) ROS_ERROR("%s", what.c_str());
    else std::fprintf(stderr, "[ERROR] %s\n", what.c_str());
  };
  const Model& m = loop_->model();
  const std::vector<PantographStatistics> st = rec->statistics(m);
  std::string why;
  const std::string text = hil::pass_stats_json(m, state, st, RunInfo{-1.0, -1.0, overruns}, &why);
  if (text.empty()) {
    error("catenary_sim_hil_udp: " + why);
    if (!params_.stats_file.empty()) stats_failed_ = true;
    return;
  }
  for (const PantographStatistics& p : st)
    ROS_INFO("catenary_sim_hil_udp: %s: mean %.1f N, std %.1f N, max %.1f N, min %.1f N, contact loss %.2f %% "
             "(%zu samples, filtered %.0f Hz)", p.name.c_str(), p.filtered.mean, p.filtered.std_dev, p.filtered.max,
             p.filtered.min, p.contact_loss_percent, p.samples, m.scene.output.filter_cutoff);
  if (params_.stats_file.empty()) return;
  try {
    write_file_atomically(params_.stats_file, text);  // (whole or not at all)
  } catch (const OutputError& e) {
    error(std::string("catenary_sim_hil_udp: ~stats_file: ") + e.what());
    stats_failed_ = true;
  }
}

int HilUdpNode::run() {
  if (const std::string e = hil::apply_realtime(realtime_options(params_)); !e.empty()) {
    ROS_FATAL("catenary_sim_hil_udp: parameter %s", e.c_str());
    return 2;
  }
  int rc = loop_->run();
  skin_->finish();  // the rig is told that the pass ended (or that the node stops)
  stop_publisher_ = true;
  if (publisher_.joinable()) publisher_.join();
  std::printf("catenary_sim_hil_udp: %s\n", hil::loop_summary(*loop_).c_str());
  std::fflush(stdout);
  report_finished_pass();  // (a pass that ended in the last period)
  if (stats_failed_ && rc == 0) rc = 1;
  if (!params_.report_file.empty()) {
    nlohmann::ordered_json j = hil::loop_report(*loop_);
    skin_->add_report(j);
    try {
      write_file_atomically(params_.report_file, j.dump(2) + "\n");
    } catch (const OutputError& e) {
      std::fprintf(stderr, "[ERROR] catenary_sim_hil_udp: ~hil/report_file: %s\n", e.what());
      if (rc == 0) rc = 1;
    }
  }
  return rc;
}

}  // namespace ros_layer
}  // namespace catenary_sim
