#include "catenary_sim/ros/virtual_rig_loop.hpp"

#include <sys/prctl.h>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "catenary_sim/MeasuredContactForce.h"
#include "catenary_sim/core/output/output_files.hpp"
#include "catenary_sim/ros/params.hpp"
#include "catenary_sim/hil/udp_loop.hpp"

namespace catenary_sim {
namespace ros_layer {

namespace {

// A pantograph the rig can stand in for (RigPantograph takes it).
bool is_lumped(const PantographSpec& ps) { return !ps.moving_force && !ps.external && !ps.masses.empty(); }

double mono_now() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

}  // namespace

VirtualRig::VirtualRig(ros::NodeHandle nh, ros::NodeHandle pnh) : nh_(nh) {
  ParamReader r(pnh, "virtual_rig", {"pantograph_scene", "rate", "extrapolate", "report_file", "transport", "simulator"});
  std::string scene_file;
  r.text("pantograph_scene", scene_file, "the path of a scene YAML file");
  if (scene_file.empty())
    throw ParamError("parameter ~pantograph_scene is required: a scene whose lumped pantographs have the "
                     "names of the external ones (e.g. config/reference_55m.yaml)");
  r.number("rate", rate_, "a number in [0, 20000] Hz (0: the node's loop rate)");
  // (a rate below 1 Hz would leave the loop asleep for seconds between measurements: no rig runs so)
  if (!std::isfinite(rate_) || !(rate_ == 0.0 || (rate_ >= 1.0 && rate_ <= 20000.0)))
    throw ParamError("parameter ~rate = " + format_given(rate_) +
                     " rejected: allowed 0 (the node's loop rate) or [1, 20000] Hz");
  r.boolean("extrapolate", extrapolate_);
  stepper_ = RigStepper(extrapolate_);
  r.text("report_file", report_file_, "a file path (empty: none)");
  check_output_param("report_file", report_file_);
  r.text("transport", transport_, "topics or udp");
  if (transport_ != "topics" && transport_ != "udp")
    throw ParamError("parameter ~transport = '" + transport_ + "' rejected: allowed topics or udp");
  r.text("simulator", simulator_, "HOST:PORT");
  try {
    scene_ = load_scene_file(scene_file);
  } catch (const SceneError& e) {
    throw ParamError("parameter ~pantograph_scene = '" + scene_file + "': " + e.what());
  }
  // The rig stands in for lumped pantographs: a scene without one it can step is refused now,
  // not at the first contact point (the simulator would wait for it for ever).
  scene_name_ = "parameter ~pantograph_scene = '" + scene_file + "'";
  std::size_t lumped = 0;
  for (const PantographSpec& ps : scene_.pantographs) {
    if (!is_lumped(ps)) continue;
    try {
      RigPantograph(ps, scene_.contact.stiffness);
    } catch (const std::invalid_argument& e) {
      throw ParamError(scene_name_ + ": " + e.what());
    }
    ++lumped;
  }
  if (lumped == 0)
    throw ParamError(scene_name_ + ": no lumped pantograph (type lumped) in the scene; allowed a scene whose lumped "
                     "pantographs have the names of the simulator's external ones (e.g. config/reference_55m.yaml)");
  if (transport_ == "udp") return;  // (run_udp: no topics)
  // Every contact point, even after a stall of the loop thread (up to 1 s at 10 kHz): the
  // pantograph is stepped through each one (a lost one: two periods against an extrapolated wire).
  ros::SubscribeOptions so = ros::SubscribeOptions::create<ContactPointArray>(
      "hil/contact_point", 10000, [this](const ContactPointArray::ConstPtr& m) { on_point(m); }, ros::VoidPtr(),
      &queue_);
  so.transport_hints = ros::TransportHints().tcpNoDelay();
  sub_ = nh_.subscribe(so);
  pub_ = nh_.advertise<MeasuredContactForce>("hil/contact_force", 10);
  ROS_INFO("virtual_rig: pantographs from %s (k0 %g N/m), waiting for %s", scene_file.c_str(),
           scene_.contact.stiffness, sub_.getTopic().c_str());
}

int VirtualRig::run_udp() {
  // The same pantograph and stepping over the packets of udp_packets.h (hil::UdpVirtualRig).
  hil::UdpRigOptions o;
  const auto colon = simulator_.rfind(':');
  int port = -1;
  try {
    if (colon != std::string::npos) port = std::stoi(simulator_.substr(colon + 1));
  } catch (const std::exception&) {
  }
  if (colon == std::string::npos || colon == 0 || port < 1 || port > 65535) {
    ROS_FATAL("virtual_rig: parameter ~simulator = '%s' rejected: allowed HOST:PORT, e.g. 127.0.0.1:47800",
              simulator_.c_str());
    return 2;
  }
  o.simulator_name = "parameter ~simulator";
  o.scene_name = scene_name_;
  o.rate_name = "parameter ~rate";
  o.bind_name = "virtual_rig's local UDP socket (any port)";
  o.simulator_address = simulator_.substr(0, colon);
  o.simulator_port = port;
  o.rate = rate_;
  o.extrapolate = extrapolate_;
  // A ROS node: it runs until the launch stops it (a new pass may come after the end), not until
  // a timeout of its own.
  o.contact_timeout = 0.0;
  o.connect_timeout = 0.0;
  try {
    hil::UdpVirtualRig rig(scene_, o);
    ROS_INFO("virtual_rig: over UDP to %s (local port %d)", simulator_.c_str(), rig.port());
    const double start = mono_now();
    const hil::RigEnd end = rig.run([this] { return running(); });
    const double wall = mono_now() - start;
    if (end == hil::RigEnd::kCannotServe) ROS_ERROR("virtual_rig: %s", rig.message().c_str());
    const auto& q = rig.sequence();
    std::printf("virtual_rig: %llu measurements sent over UDP, %llu missed ticks; contact points %llu received, %llu "
                "lost; round trip p50 %.1f us, p99 %.1f us, max %.1f us\n",
                static_cast<unsigned long long>(rig.sent()), static_cast<unsigned long long>(rig.missed_ticks()),
                static_cast<unsigned long long>(q.received()), static_cast<unsigned long long>(q.lost()),
                rig.round_trip().quantile(0.5) * 1e6, rig.round_trip().quantile(0.99) * 1e6, rig.round_trip().max() * 1e6);
    std::fflush(stdout);
    if (!write_report(rig.sent(), rig.missed_ticks(), wall, rig.round_trip())) return 1;
    if (end == hil::RigEnd::kCannotServe) return 2;
  } catch (const hil::HilError& e) {
    ROS_FATAL("virtual_rig: %s", e.what());
    return 2;
  }
  return 0;
}

bool VirtualRig::write_report(std::uint64_t sent, std::uint64_t missed, double wall, const LatencyHistogram& round_trip) {
  if (report_file_.empty()) return true;
  nlohmann::ordered_json j;  // (a non-finite number is written as null)
  j["measurements"] = sent;
  j["missed_ticks"] = missed;
  j["wall_s"] = wall;
  j["round_trip"] = {{"count", round_trip.count()},
                     {"p50_s", round_trip.quantile(0.5)},
                     {"p99_s", round_trip.quantile(0.99)},
                     {"max_s", round_trip.max()}};
  try {
    write_file_atomically(report_file_, j.dump() + "\n");
  } catch (const OutputError& e) {
    // (after a shutdown rosconsole no longer prints)
    std::fprintf(stderr, "[ERROR] virtual_rig: ~report_file: %s\n", e.what());
    return false;
  }
  return true;
}

int VirtualRig::run() {
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);  // wake-ups on time (this thread)
  if (transport_ == "udp") return run_udp();
  while (running() && !have_) queue_.callAvailable(ros::WallDuration(0.1));
  if (!running()) return 0;
  const double period = rate_ > 0.0 ? 1.0 / rate_ : dt_ * steps_per_period_;
  ROS_INFO("virtual_rig: %zu pantograph(s), loop %g Hz, dt %g ms, %s wire between contact points", stepper_.size(),
           1.0 / period, dt_ * 1e3, extrapolate_ ? "extrapolated" : "held");
  double next = mono_now() + 0.25 * period;
  const double start = mono_now();
  while (running()) {
    // Take contact points as they come (stepping the pantograph up to each at once) until the
    // tick, then send the contact force: the measurement, as a rig samples its load cell.
    for (double now = mono_now(); now < next && running(); now = mono_now())
      queue_.callAvailable(ros::WallDuration(next - now));
    queue_.callAvailable(ros::WallDuration(0.0));
    send();
    next = hil::next_rig_tick(next, period, mono_now(), missed_);
  }
  const double wall = mono_now() - start;
  std::printf("virtual_rig: %llu measurements in %.1f s, %llu missed ticks; round trip (sent -> contact point "
              "using it received) p50 %.1f us, p99 %.1f us, max %.1f us over %llu\n",
              static_cast<unsigned long long>(sent_), wall, static_cast<unsigned long long>(missed_),
              round_trip_.quantile(0.5) * 1e6, round_trip_.quantile(0.99) * 1e6, round_trip_.max() * 1e6,
              static_cast<unsigned long long>(round_trip_.count()));
  std::fflush(stdout);
  if (!write_report(sent_, missed_, wall, round_trip_)) return 1;
  return failed_ ? 2 : 0;
}

void VirtualRig::on_point(const ContactPointArray::ConstPtr& msg) {
  if (!(msg->dt > 0.0 && msg->dt < 1.0) || msg->steps_per_period == 0) return;  // (also NaN)
  std::vector<std::vector<WirePoint>> points;
  for (const ContactPoint& c : msg->pantographs) points.push_back(wire_points(c));
  if (stepper_.needs_restart(msg->pass_count, msg->step, msg->pantographs.size())) {
    std::vector<RigPantograph> rigs;
    for (const ContactPoint& c : msg->pantographs) {
      const PantographSpec* spec = nullptr;
      for (const PantographSpec& ps : scene_.pantographs)
        if (ps.name == c.name && is_lumped(ps)) spec = &ps;
      if (!spec) {
        // The rig cannot answer: it stops (and the launch with it) rather than leave the simulator
        // waiting for ever.
        ROS_FATAL("virtual_rig: %s: no lumped pantograph named '%s' (the simulator's external pantograph); allowed "
                  "a scene whose lumped pantographs have the names of the external ones", scene_name_.c_str(),
                  c.name.c_str());
        have_ = false;
        stepper_.clear();
        failed_ = true;
        stop_ = true;
        return;
      }
      rigs.emplace_back(*spec, scene_.contact.stiffness);
    }
    stepper_.restart(std::move(rigs), std::move(points), msg->pass_count, msg->step, msg->dt, msg->speed);
    if (have_) ROS_INFO("virtual_rig: pass %u: pantograph(s) reset at the static state", msg->pass_count);
  } else {
    stepper_.advance(msg->step, points, msg->dt, msg->speed);
  }
  have_ = true;
  frame_ = msg->header.frame_id;
  step_ = msg->step;
  dt_ = msg->dt;
  steps_per_period_ = msg->steps_per_period;
  // Round trip of the measurement this contact point used.
  const auto it = sent_at_.find(msg->measurement_step);
  if (msg->measurement_step > 0 && it != sent_at_.end()) {
    round_trip_.add(mono_now() - it->second);
    sent_at_.erase(it);
  }
}

void VirtualRig::send() {
  if (!have_) return;
  // (a shared pointer: the node in the same process, HilNodelet, gets it without a copy)
  const boost::shared_ptr<MeasuredContactForce> m = boost::make_shared<MeasuredContactForce>();
  m->header.stamp = ros::Time::now();
  m->header.frame_id = frame_;  // the frame of the contact point answered (the line frame)
  m->step = step_;
  for (std::size_t i = 0; i < stepper_.size(); ++i) m->force.push_back(stepper_.force(i));
  pub_.publish(m);
  ++sent_;
  sent_at_.emplace(step_, mono_now());  // (a repeated step keeps its first time)
  while (sent_at_.size() > 256) sent_at_.erase(sent_at_.begin());
}

}  // namespace ros_layer
}  // namespace catenary_sim
