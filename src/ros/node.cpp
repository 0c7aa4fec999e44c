#include "catenary_sim/ros/node.hpp"

#include <rosgraph_msgs/Clock.h>
#include <std_msgs/String.h>
#include <tf2_msgs/TFMessage.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <iomanip>
#include <cstdio>
#include <algorithm>
#include <limits>
#include <sstream>

#include "catenary_sim/ContactForceArray.h"
#include "catenary_sim/PantographStateArray.h"
#include "catenary_sim/LineState.h"
#include "catenary_sim/PassEvent.h"
#include "catenary_sim/WireShapeArray.h"
#include "catenary_sim/core/output/output_files.hpp"
#include "catenary_sim/core/output/pass_files.hpp"
#include "catenary_sim/tools/report_launcher.hpp"
#include "catenary_sim/ros/conversions.hpp"
#include "catenary_sim/ros/markers.hpp"

namespace catenary_sim {
namespace ros_layer {

namespace {
// Sample rate of the recorder's decimated time series without a report (statistics use every step).
constexpr double kRecorderRowRate = 10.0;

// The report's data files and pictures go in the directory of the page.
std::string report_directory(const std::string& html) {
  const std::size_t slash = html.rfind('/');
  return slash == std::string::npos ? "." : slash == 0 ? "/" : html.substr(0, slash);
}

// At real_time_factor > 0, a tick may take this many times its nominal share of steps before the
// backlog is dropped (counted as an overrun) instead of trying to catch up.
constexpr double kCatchUp = 2.0;
}  // namespace

SimulationNode::SimulationNode(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(nh), pnh_(pnh), params_(load_params(pnh)), updater_(nh, pnh) {
  params_.scene = resolve_scene_path(params_.scene);
  const Scene scene = load_scene(params_);
  try {
    sim_ = std::make_unique<Simulation>(scene);
  } catch (const SceneError& e) {
    throw ParamError("parameter ~scene = '" + params_.scene + "': " + e.what());
  }
  try {
    view_pantograph_ = view_pantograph_index(sim_->model(), params_.view_pantograph, "~view_pantograph");
  } catch (const std::invalid_argument& e) {
    throw ParamError(e.what());
  }
  std::string err;
  if (!sim_->set_max_acceleration(params_.max_acceleration, &err)) throw ParamError("parameter ~max_acceleration: " + err);
  if (!params_.report_file.empty()) {
    // The report's data files go beside it: all of them writable now, not after the pass.
    try {
      check_pass_files_writable(report_directory(params_.report_file), sim_->model());
    } catch (const OutputError& e) {
      throw ParamError("parameter ~report_file = '" + params_.report_file + "' rejected: " + e.what());
    }
  }
  restart_recording();

  paused_ = params_.paused;

  contact_pub_ = nh_.advertise<ContactForceArray>("contact_force", 10);
  pantograph_pub_ = nh_.advertise<PantographStateArray>("pantograph_state", 10);
  shape_pub_ = nh_.advertise<WireShapeArray>("wire_shape", 2);
  marker_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("markers", 2);
  // (the broadcaster's own topic, advertised again for the connect callback: one publication)
  tf_hold_pub_ = nh_.advertise<tf2_msgs::TFMessage>(
      "/tf", 100, [this](const ros::SingleSubscriberPublisher& pub) { on_tf_subscriber(pub); });
  if (params_.publish_clock) clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 10);
  status_pub_ = nh_.advertise<std_msgs::String>("pass_status", 1, true);
  // The scene itself, latched, so that a recording carries it and its replay needs no scene file.
  scene_pub_ = pnh_.advertise<std_msgs::String>("scene_yaml", 1, true);
  std_msgs::String text;
  text.data = scene_yaml_message(params_.scene);
  scene_pub_.publish(text);
  events_pub_ = nh_.advertise<PassEvent>("events", 100);
  line_state_pub_ = nh_.advertise<LineState>("line_state", 10);
  // A 3-D line (stagger, curve, wind or sway) also says where each strip meets the wire across it.
  if (sim_->model().lateral) lateral_pub_ = nh_.advertise<LateralContactArray>("lateral_contact", 10);
  speed_sub_ = nh_.subscribe("cmd/train_speed", 10, &SimulationNode::on_speed, this);
  uplift_sub_ = nh_.subscribe("cmd/uplift_force", 10, &SimulationNode::on_uplift, this);
  reset_srv_ = pnh_.advertiseService("reset", &SimulationNode::on_reset, this);
  pause_srv_ = pnh_.advertiseService("set_paused", &SimulationNode::on_set_paused, this);
  step_srv_ = pnh_.advertiseService("step", &SimulationNode::on_step, this);

  updater_.setHardwareID("catenary_sim/" + scene.name);
  updater_.add("simulation", this, &SimulationNode::diagnose);
  // After the parameters: the server starts from the values on the parameter server (validated
  // above) and calls on_reconfigure once with them.
  reconfigure_ = std::make_unique<dynamic_reconfigure::Server<NodeConfig>>(pnh_);
  reconfigure_->setCallback([this](NodeConfig& c, uint32_t level) { on_reconfigure(c, level); });

  const Model& m = sim_->model();
  ROS_INFO("catenary_sim: scene %s: %zu spans, %.1f m, %d DOFs, dt %.4g ms (stability limit %.4g ms), "
           "speed %.1f km/h, real_time_factor %g, at_end %s",
           scene.name.c_str(), scene.spans.size(), m.line_length, m.n_dof, m.dt * 1e3, m.dt_critical * 1e3,
           scene.train_speed * 3.6, params_.real_time_factor, to_string(params_.at_end));
  for (const std::string& w : m.warnings) ROS_WARN("catenary_sim: %s", w.c_str());
}

void SimulationNode::restart_recording() {
  loss_since_.assign(sim_->model().pantographs.size(), std::nan(""));
  loss_station_ = loss_since_;
  // With a report, the time series as the scene asks for them (simulate_pass's); else a few rows
  // (the statistics use every step either way).
  const double rows = params_.report_file.empty() ? kRecorderRowRate : sim_->model().scene.output.sample_rate;
  recorder_ = std::make_unique<PassRecorder>(sim_->model(), rows);
  recorder_->record(sim_->model(), sim_->state());
  lateral_recorder_ = std::make_unique<LateralRecorder>(sim_->model(), rows);  // records nothing on a 2-D line
  lateral_recorder_->record(sim_->model(), sim_->state());
  chart_.clear(params_.chart_window);
}

void SimulationNode::publish_line_state(const ros::Time& stamp) {
  line_state_pub_.publish(to_line_state(sim_->model(), sim_->state(), *recorder_, stamp, params_.line_frame));
}

void SimulationNode::reanchor() {
  wall_anchor_ = ros::WallTime::now();
  sim_anchor_ = sim_->state().time;
}

int SimulationNode::run() {
  waiting_ = true;
  publish_status();
  publish(true);
  wait_for_viewer();
  wait_for_recorder();
  if (params_.start_delay > 0.0 && ros::ok()) {
    ROS_INFO("catenary_sim: starting in %g s (~start_delay)", params_.start_delay);
    const ros::WallTime start = ros::WallTime::now() + ros::WallDuration(params_.start_delay);
    while (ros::ok() && ros::WallTime::now() < start) {
      ros::spinOnce();
      publish(false);
      ros::WallDuration(0.02).sleep();
    }
  }
  waiting_ = false;
  if (paused_) ROS_INFO("catenary_sim: paused (~paused); start with: rosservice call %s false",
                        pnh_.resolveName("set_paused").c_str());
  wall_start_ = ros::WallTime::now();
  diag_wall_ = wall_start_;
  diag_sim_ = sim_->state().time;
  reanchor();
  publish(true);
  ros::WallTime next_tick = ros::WallTime::now();
  while (ros::ok() && !exit_requested_) {
    ros::spinOnce();
    if (exit_requested_) break;
    advance(next_tick + ros::WallDuration(1.0 / params_.publish_rate));
    if (sim_->finished() || ended_) track_contact_loss();  // closes a loss still open at the end
    handle_end();
    if (report_pid_ > 0) reap_report(false);
    publish(false);
    publish_status();
    // Health on the wall clock: with simulated time the updater's own timer would stop while paused.
    const ros::WallTime now = ros::WallTime::now();
    if (now >= next_diagnostics_wall_) {
      updater_.force_update();
      next_diagnostics_wall_ = now + ros::WallDuration(1.0);
    }
    const ros::WallDuration period(1.0 / params_.publish_rate);  // may change (dynamic_reconfigure)
    next_tick += period;
    if (next_tick > now) {
      (next_tick - now).sleep();
    } else {
      next_tick = now;  // behind: do not try to catch up on ticks
    }
  }
  if (report_pid_ > 0) {
    ROS_INFO("catenary_sim: waiting for the pass report to be drawn (%s)", params_.report_file.c_str());
    reap_report(true);
  }
  return exit_code_;
}

void SimulationNode::wait_for_viewer() {
  // rviz subscribes before its displays have drawn the first frame: give it a second.
  wait_for_subscriber(marker_pub_, params_.wait_for_viewer, "a viewer (rviz)", "wait_for_viewer", 1.0);
}

void SimulationNode::wait_for_recorder() {
  // rosbag's other subscriptions connect in the same moment: half a second covers them.
  wait_for_subscriber(pantograph_pub_, params_.wait_for_recorder, "a recorder", "wait_for_recorder", 0.5);
}

void SimulationNode::wait_for_subscriber(const ros::Publisher& pub, double wait_s, const char* who,
                                         const char* param, double settle_s) {
  if (!(wait_s > 0.0)) return;
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(wait_s);
  if (pub.getNumSubscribers() == 0)
    ROS_INFO("catenary_sim: waiting up to %g s for %s to subscribe to %s (~%s)", wait_s, who, pub.getTopic().c_str(),
             param);
  while (ros::ok() && pub.getNumSubscribers() == 0 && ros::WallTime::now() < give_up) {
    ros::spinOnce();
    publish(false);
    ros::WallDuration(0.05).sleep();
  }
  if (pub.getNumSubscribers() == 0) {
    ROS_WARN("catenary_sim: no subscriber (%s) within %g s; starting anyway", who, wait_s);
    return;
  }
  for (const ros::WallTime settled = ros::WallTime::now() + ros::WallDuration(settle_s);
       ros::ok() && ros::WallTime::now() < settled;) {
    ros::spinOnce();
    publish(true);
    ros::WallDuration(0.05).sleep();
  }
}

void SimulationNode::publish_status() {
  const State& s = sim_->state();
  std::string now = "running";
  if (s.status == StepStatus::kDiverged) now = "diverged";
  else if (ended_) now = "ended";
  else if (waiting_) now = "waiting";
  else if (paused_) now = "paused";
  if (now == status_) return;
  status_ = now;
  std_msgs::String m;
  m.data = now;
  status_pub_.publish(m);
}

void SimulationNode::track_contact_loss() {
  const Model& m = sim_->model();
  const State& s = sim_->state();
  for (std::size_t p = 0; p < m.pantographs.size(); ++p) {
    if (m.pantographs[p].external) continue;
    const bool lost = !(total_contact_force(m, s, static_cast<int>(p)) > 0.0);
    const double station = s.front - m.pantographs[p].position + s.line_offset;
    const bool in_loss = !std::isnan(loss_since_[p]);
    if (lost && !in_loss) {
      loss_since_[p] = s.time;
      loss_station_[p] = station;
    } else if (in_loss && (!lost || sim_->finished() || ended_)) {
      PassEvent e;
      e.header.stamp = ros::Time(loss_since_[p]);
      e.header.frame_id = params_.line_frame;
      e.kind = PassEvent::CONTACT_LOSS;
      e.pantograph = m.pantographs[p].name;
      e.station = loss_station_[p];
      e.simulation_time = loss_since_[p];
      e.duration = s.time - loss_since_[p];
      e.length = station - loss_station_[p];
      events_pub_.publish(e);
      loss_since_[p] = std::nan("");
    }
  }
}

bool SimulationNode::holding() const {
  return paused_ || ended_ || waiting_ || sim_->finished() || sim_->state().status != StepStatus::kOk;
}

void SimulationNode::on_tf_subscriber(const ros::SingleSubscriberPublisher& pub) {
  // While running, the next tick broadcasts a new time; sending it here as well could give the new
  // listener the same stamp twice.
  if (!holding() || last_published_time_ != sim_->state().time) return;
  const State& s = sim_->state();
  const ros::Time stamp = sim_stamp(s.time, 0.0);
  tf2_msgs::TFMessage msg;
  msg.transforms = to_transforms(sim_->model(), s, stamp, params_.line_frame);
  // train_view only once the markers of the hold have broadcast it (else they will, to everyone).
  if (view_sent_ && last_view_stamp_ == stamp)
    for (const auto& t : to_view_transforms(sim_->model(), s, stamp, params_.line_frame, view_pantograph_)) msg.transforms.push_back(t);
  pub.publish(msg);
}

std::int64_t SimulationNode::do_steps(std::int64_t n, const ros::WallTime* deadline) {
  const Model& m = sim_->model();
  std::int64_t done = 0;
  for (; done < n; ++done) {
    if (sim_->finished()) break;
    if (sim_->step() != StepStatus::kOk) break;
    const State& s = sim_->state();
    recorder_->record(m, s);
    lateral_recorder_->record(m, s);
    track_contact_loss();  // every step: the events resolve dt, not the publishing tick
    // The chart's samples on simulated time (a thousand per window), also when ~step jumps ahead.
    if (params_.strip_chart && chart_.due(s.time, 1e-3 * params_.chart_window)) chart_.sample(m, s);
    if (deadline && (done & 31) == 31 && ros::WallTime::now() >= *deadline) {
      ++done;
      break;
    }
  }
  return done;
}

void SimulationNode::advance(const ros::WallTime& tick_deadline) {
  if (paused_ || ended_) return;
  if (sim_->finished() || sim_->state().status != StepStatus::kOk) return;
  const double dt = sim_->model().dt;
  if (params_.real_time_factor <= 0.0) {
    // As fast as possible: step until the tick is due, then publish.
    if (do_steps(std::numeric_limits<std::int64_t>::max(), &tick_deadline) > 0) ++chunks_;
    return;
  }
  const ros::WallTime now = ros::WallTime::now();
  const std::int64_t due = steps_due((now - wall_anchor_).toSec(), params_.real_time_factor, dt,
                                     sim_->state().time - sim_anchor_);
  const double nominal = params_.real_time_factor / (params_.publish_rate * dt);
  // (at most 1e15 steps: the conversion of a larger double, from a tiny dt, is undefined)
  const std::int64_t limit = static_cast<std::int64_t>(std::min(std::ceil(kCatchUp * nominal), 1e15)) + 1;
  const std::int64_t want = std::min(due, limit);
  const std::int64_t done = do_steps(want, &tick_deadline);
  if (done > 0) ++chunks_;
  if (due > limit || (done < want && !sim_->finished() && sim_->state().status == StepStatus::kOk)) {
    // Could not keep up: drop the backlog (dt is never stretched; the achieved factor drops).
    ++overruns_;
    ROS_WARN_THROTTLE(5.0, "catenary_sim: overrun: %lld steps due, %lld taken this tick (%lld overruns so far); "
                      "real_time_factor %g is not reached",
                      static_cast<long long>(due), static_cast<long long>(done), static_cast<long long>(overruns_),
                      params_.real_time_factor);
    reanchor();
  }
}

void SimulationNode::handle_end() {
  if (ended_) return;
  const State& s = sim_->state();
  if (s.status == StepStatus::kDiverged) {
    ended_ = true;
    ROS_ERROR("catenary_sim: %s", sim_->status_message().c_str());
    if (params_.at_end == AtEnd::kExit) {
      exit_code_ = 1;
      exit_requested_ = true;
      publish(true);
      ros::shutdown();
    }
    return;
  }
  if (!sim_->finished()) return;
  // (finished() is true as soon as the front reaches the end, before step() marks the state)
  if (s.status == StepStatus::kDewired) ROS_WARN("catenary_sim: %s", sim_->status_message().c_str());
  char what[256];
  std::snprintf(what, sizeof what, "pass finished at t = %.4f s (train front at %.2f m), %lld chunks, %lld overruns",
                s.time, s.front + s.line_offset, static_cast<long long>(chunks_), static_cast<long long>(overruns_));
  switch (params_.at_end) {
    case AtEnd::kStop:
      ended_ = true;
      ROS_INFO("catenary_sim: %s; holding the last state (at_end stop)", what);
      report_statistics();
      break;
    case AtEnd::kLoop:
      ROS_INFO("catenary_sim: %s; starting again (at_end loop)", what);
      report_statistics();
      publish(true);
      sim_->reset(true);
      restart_recording();
      reanchor();
      break;
    case AtEnd::kExit:
      ended_ = true;
      ROS_INFO("catenary_sim: %s; exiting (at_end exit)", what);
      publish(true);
      report_statistics();
      if (report_pid_ > 0) {  // (before the shutdown, which silences the log)
        ROS_INFO("catenary_sim: waiting for the pass report to be drawn (%s)", params_.report_file.c_str());
        reap_report(true);
      }
      exit_requested_ = true;
      ros::shutdown();
      break;
  }
}

void SimulationNode::report_statistics() {
  const Model& m = sim_->model();
  const std::vector<PantographStatistics> stats = recorder_->statistics(m);
  for (const PantographStatistics& s : stats) {
    ROS_INFO("catenary_sim: %s: mean %.1f N, std %.1f N, max %.1f N, min %.1f N, stat max %.1f N, stat min %.1f N, "
             "contact loss %.2f %%, max uplift at steady arm %.1f mm (%zu samples, filtered %.0f Hz)",
             s.name.c_str(), s.filtered.mean, s.filtered.std_dev, s.filtered.max, s.filtered.min, s.filtered.stat_max,
             s.filtered.stat_min, s.contact_loss_percent, s.max_uplift_at_support_m * 1e3, s.samples,
             m.scene.output.filter_cutoff);
  }
  write_report();
  if (params_.stats_file.empty()) return;
  // The same document as simulate_pass's stats.json and the report's (one code path).
  const std::string json =
      pass_statistics_json(m, sim_->state(), *recorder_, RunInfo{(ros::WallTime::now() - wall_start_).toSec(), -1.0, overruns_},
                           lateral_recorder_.get(), sim_->state().status == StepStatus::kDewired);
  // Whole or not at all (checked writable at start-up; a full disk is still possible): a failure
  // is an error and the node's exit code becomes 1, whenever it exits.
  try {
    write_file_atomically(params_.stats_file, json);
    ROS_INFO("catenary_sim: statistics written to %s", params_.stats_file.c_str());
  } catch (const OutputError& e) {
    ROS_ERROR("catenary_sim: ~stats_file: %s", e.what());
    exit_code_ = 1;
  }
}

void SimulationNode::write_report() {
  if (params_.report_file.empty()) return;
  if (report_pid_ > 0) {
    reap_report(false);
    if (report_pid_ > 0) {  // (a loop faster than matplotlib: the next pass's report follows)
      ROS_WARN("catenary_sim: the last pass's report is still being drawn; no report for this pass");
      return;
    }
  }
  const std::string dir = report_directory(params_.report_file);
  try {
    write_pass_files(dir, sim_->model(), sim_->state(), *recorder_,
                     RunInfo{(ros::WallTime::now() - wall_start_).toSec(), -1.0, overruns_}, lateral_recorder_.get(),
                     sim_->state().status == StepStatus::kDewired);
  } catch (const OutputError& e) {
    ROS_ERROR("catenary_sim: ~report_file: %s", e.what());
    exit_code_ = 1;
    return;
  }
  std::string why;
  report_pid_ = start_pass_report(dir, params_.report_file, true, &why);
  if (report_pid_ < 0) {
    ROS_ERROR("catenary_sim: ~report_file: %s (the pass's data files are in %s)", why.c_str(), dir.c_str());
    exit_code_ = 1;
    return;
  }
  ROS_INFO("catenary_sim: pass files written to %s; drawing the report %s", dir.c_str(), params_.report_file.c_str());
}

void SimulationNode::reap_report(bool block) {
  const int rc = pass_report_status(report_pid_, block);
  if (rc == kReportRunning) return;
  report_pid_ = -1;
  if (rc == 0) {
    ROS_INFO("catenary_sim: pass report written to %s", params_.report_file.c_str());
  } else {
    ROS_ERROR("catenary_sim: ~report_file: scripts/pass_report failed (exit %d); the pass's data files are written",
              rc);
    exit_code_ = 1;
  }
}

void SimulationNode::publish(bool force) {
  const Model& m = sim_->model();
  const State& s = sim_->state();
  if (params_.strip_chart && chart_.empty()) chart_.sample(m, s);  // the initial state
  const ros::WallTime now = ros::WallTime::now();
  const ros::Time stamp = sim_stamp(s.time, 0.0);
  const bool advanced = s.time > last_published_time_;
  const bool shape_due = (now - last_shape_wall_).toSec() >= 1.0 / params_.shape_rate;
  // Markers: at marker_rate while the state changes, at shape_rate while it holds.
  const bool markers_new = s.time != last_marker_time_;
  const bool markers_due = force || (markers_new ? now >= next_marker_wall_ : shape_due);

  // While the simulation holds (paused, stopped), the state topics are repeated at shape_rate with
  // their unchanged stamp; tf and /clock are only sent for a new time.
  if (advanced || force || shape_due) {
    // /clock for every new time and, while holding, again at shape_rate: a node started with
    // /use_sim_time during a pause gets its time at once (gazebo_ros does the same).
    if (params_.publish_clock) {
      rosgraph_msgs::Clock c;
      c.clock = stamp;
      clock_pub_.publish(c);
    }
    if (advanced || force) {
      if (advanced) tf_.sendTransform(to_transforms(m, s, stamp, params_.line_frame));
    }
    contact_pub_.publish(to_contact_force(m, s, stamp, params_.line_frame));
    pantograph_pub_.publish(to_pantograph_state(m, s, stamp, params_.line_frame));
    if (m.lateral) lateral_pub_.publish(to_lateral_contact(m, s, stamp, params_.line_frame));
    last_published_time_ = s.time;
    if (shape_due || force) {
      last_shape_wall_ = now;
      shape_pub_.publish(to_wire_shape(m, s, params_.shape_resolution, stamp, params_.line_frame));
      publish_line_state(stamp);
    }
  }

  if (markers_due) {
    // Fixed schedule (no drift from the tick quantisation); after a stall, restart from now.
    const ros::WallDuration period(1.0 / params_.marker_rate);
    next_marker_wall_ = (now - next_marker_wall_ > period) ? now + period : next_marker_wall_ + period;
    if (marker_pub_.getNumSubscribers() > 0) {
      MarkerOptions o;
      o.frame = params_.line_frame;
      o.vertical_scale = params_.vertical_scale;
      o.lateral_scale = params_.lateral_scale;
      o.shape_resolution = params_.shape_resolution;
      visualization_msgs::MarkerArray arr = to_markers(m, s, stamp, o);
      if (params_.strip_chart) {
        // The heads-up line and the statistics so far (unfiltered: the filtered ones need the
        // whole pass, zero-phase), in the chart's panel, which follows the train.
        std::ostringstream head;
        head << heads_up_position(m, s) << "  " << std::fixed << std::setprecision(2);
        if (paused_ || waiting_ || ended_ || sim_->finished()) head << (paused_ ? "paused" : ended_ || sim_->finished() ? "ended" : "waiting");
        else head << achieved_rtf_ << "x real time";
        head << "  vertical x" << std::setprecision(0) << params_.vertical_scale;
        if (m.lateral && params_.lateral_scale != 1.0) head << "  lateral x" << params_.lateral_scale;
        const visualization_msgs::MarkerArray chart = chart_.markers(m, head.str(), stamp);
        arr.markers.insert(arr.markers.end(), chart.markers.begin(), chart.markers.end());
      }
      marker_pub_.publish(arr);
      // The camera's frame moves with the markers, same stamp. A repeated stamp (holding) is not
      // sent again: tf2 would warn TF_REPEATED_DATA, and the last transform stays in effect.
      if (!view_sent_ || stamp != last_view_stamp_) {
        tf_.sendTransform(to_view_transforms(m, s, stamp, params_.line_frame, view_pantograph_));
        last_view_stamp_ = stamp;
        view_sent_ = true;
      }
      last_marker_time_ = s.time;
    }
  }
}

void SimulationNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  const Model& m = sim_->model();
  const State& s = sim_->state();
  const ros::WallTime now = ros::WallTime::now();
  const double wall = (now - diag_wall_).toSec();
  const double rtf = wall > 0.0 ? (s.time - diag_sim_) / wall : 0.0;
  const std::int64_t new_overruns = overruns_ - diag_overruns_;
  diag_wall_ = now;
  diag_sim_ = s.time;
  diag_overruns_ = overruns_;
  const double margin = m.dt / m.dt_critical;

  // Health only: is the simulation computing, in time, within its stability limit. What the
  // physics does (contact loss, slack droppers, uplift) is a result: on `events` and the topics.
  using diagnostic_msgs::DiagnosticStatus;
  const bool holding = paused_ || ended_ || waiting_ || sim_->finished();
  if (s.status == StepStatus::kDiverged) stat.summary(DiagnosticStatus::ERROR, sim_->status_message());
  else if (new_overruns > 0) stat.summary(DiagnosticStatus::WARN, "overruns: real_time_factor not reached");
  else if (margin > 1.0) stat.summary(DiagnosticStatus::WARN, "dt above the stability limit");
  else if (waiting_) stat.summary(DiagnosticStatus::OK, "waiting to start");
  else if (paused_) stat.summary(DiagnosticStatus::OK, "paused");
  else if (ended_ || sim_->finished()) stat.summary(DiagnosticStatus::OK, "pass finished");
  else stat.summary(DiagnosticStatus::OK, "running");

  achieved_rtf_ = holding ? 0.0 : rtf;
  if (holding) stat.add("real_time_factor (achieved)", "not stepping (" + status_ + ")");
  else stat.add("real_time_factor (achieved)", rtf);
  stat.add("real_time_factor (requested, 0 = max)", params_.real_time_factor);
  stat.add("chunks", chunks_);
  stat.add("overruns", overruns_);
  stat.add("stability margin dt/dt_critical", margin);
  stat.add("dt [s]", m.dt);
  stat.add("sim time [s]", s.time);
  stat.add("steps", s.steps);
  if (have_command_) stat.add("age of last command [s]", (now - last_command_wall_).toSec());
  else stat.add("age of last command [s]", "no command yet");
  stat.add("paused", paused_);
}

}  // namespace ros_layer
}  // namespace catenary_sim
