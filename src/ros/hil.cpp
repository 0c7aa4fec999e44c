#include "catenary_sim/ros/hil.hpp"
#include "catenary_sim/ros/params.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace catenary_sim {
namespace ros_layer {

namespace {


constexpr double kBinWidth = 1e-6;   // s
constexpr std::size_t kBins = 10000;  // up to 10 ms

}  // namespace

HilTiming hil_timing(double rate, std::optional<double> scene_dt, double auto_dt) {
  if (!std::isfinite(rate) || rate < 1000.0 || rate > 10000.0)
    throw ParamError("parameter ~hil/rate = " + format_number(rate) + " rejected: allowed [1000, 10000] Hz");
  HilTiming t;
  t.period = 1.0 / rate;
  if (scene_dt) {
    const double k = t.period / *scene_dt;
    const double kr = std::round(k);
    if (kr < 1.0 || std::fabs(k - kr) > 1e-6 * kr) {
      const int k_auto = static_cast<int>(std::ceil(t.period / *scene_dt - 1e-9));
      throw ParamError("numerics.dt = " + format_number(*scene_dt) + " s of ~scene does not divide the loop period " +
                       format_number(t.period) + " s of ~hil/rate = " + format_number(rate) +
                       " Hz: the period must be a whole number of core steps; use numerics.dt = period / k, e.g. " +
                       format_number(t.period / std::max(1, k_auto)) + " s, or numerics.dt: auto (the node then chooses it)");
    }
    t.steps_per_period = static_cast<int>(kr);
  } else {
    if (!(auto_dt > 0.0)) throw ParamError("~scene: the automatic dt is " + format_number(auto_dt) + " s");
    t.steps_per_period = static_cast<int>(std::ceil(t.period / auto_dt - 1e-9));
  }
  t.dt = t.period / t.steps_per_period;
  return t;
}

void MeasurementHold::accept(const std::vector<double>& force, double arrival, double measured, std::uint64_t step) {
  previous_ = force_;
  previous_time_ = time_;
  force_ = force;
  arrival_ = arrival;
  // The measurement's own time when it has one, else its arrival: only differences are used.
  time_ = measured > 0.0 ? measured : arrival;
  previous_stamped_ = stamped_;
  stamped_ = measured > 0.0;
  step_ = step;
  ++count_;
}

double MeasurementHold::value(std::size_t i, double t, bool extrapolate, double horizon) const {
  if (i >= force_.size()) return 0.0;
  const double f = force_[i];
  // (a stamped and an unstamped measurement: two clocks, no slope)
  if (!extrapolate || count_ < 2 || stamped_ != previous_stamped_) return f;
  const double span = time_ - previous_time_;
  if (!(span > 0.0) || span > 1.0) return f;
  const double ahead = std::clamp(t - arrival_, 0.0, std::max(0.0, horizon));
  return f + (f - previous_[i]) / span * ahead;
}

double hold_ramp_force(double from, double to, double elapsed, double ramp) {
  if (!(ramp > 0.0) || elapsed >= ramp) return to;
  if (elapsed <= 0.0) return from;
  return from + (to - from) * (elapsed / ramp);
}

LatencyHistogram::LatencyHistogram() : bins_(kBins, 0) {}

void LatencyHistogram::add(double s) {
  if (!std::isfinite(s)) return;
  s = std::max(0.0, s);
  const std::size_t b = std::min(kBins - 1, static_cast<std::size_t>(s / kBinWidth));
  ++bins_[b];
  ++count_;
  sum_ += s;
  max_ = std::max(max_, s);
}

double LatencyHistogram::quantile(double q) const {
  if (count_ == 0) return 0.0;
  const double target = std::clamp(q, 0.0, 1.0) * static_cast<double>(count_);
  std::uint64_t cum = 0;
  for (std::size_t b = 0; b < kBins; ++b) {
    cum += bins_[b];
    if (static_cast<double>(cum) >= target && cum > 0)
      return b + 1 == kBins ? max_ : std::min(max_, (b + 1) * kBinWidth);  // (the last bin: beyond 10 ms)
  }
  return max_;
}

void LatencyHistogram::clear() {
  std::fill(bins_.begin(), bins_.end(), 0);
  count_ = 0;
  max_ = sum_ = 0.0;
}

std::vector<int> external_pantographs(const Model& m) {
  std::vector<int> out;
  for (std::size_t p = 0; p < m.pantographs.size(); ++p)
    if (m.pantographs[p].external) out.push_back(static_cast<int>(p));
  return out;
}

ContactPointArray to_contact_points(const Model& m, const State& s, const ros::Time& stamp, const std::string& frame,
                                    int steps_per_period, std::vector<ContactPointMotion>& scratch) {
  ContactPointArray out;
  out.header.stamp = stamp;
  out.header.frame_id = frame;
  out.simulation_time = s.time;
  out.step = static_cast<std::uint64_t>(s.steps);
  out.dt = m.dt;
  out.steps_per_period = static_cast<std::uint32_t>(steps_per_period);
  out.speed = s.speed;
  out.mode = ContactPointArray::RUNNING;
  for (int wi : m.contact_wires) out.contact_wires.push_back(m.wires[wi].name);
  const std::size_t nw = m.contact_wires.size();
  for (std::size_t p = 0; p < m.pantographs.size(); ++p) {
    const Pantograph& pg = m.pantographs[p];
    if (!pg.external) continue;
    ContactPoint c;
    c.name = pg.name;
    c.position = pantograph_position(m, s, static_cast<int>(p));
    c.measurement_age = -1.0;
    contact_point_motion(m, s, static_cast<int>(p), scratch);
    // Per collector: the lowest contact wire under it (the one a force-driven collector pushes).
    double h = 0.0, v = 0.0, a = 0.0, pv = 0.0;
    int under = 0;
    for (std::size_t ci = 0; ci < pg.collectors.size(); ++ci) {
      const ContactPointMotion* low = nullptr;
      for (std::size_t k = 0; k < nw; ++k) {
        const ContactPointMotion& cm = scratch[ci * nw + k];
        if (cm.on_wire && (!low || cm.height < low->height)) low = &cm;
      }
      if (!low) continue;
      h += low->height;
      v += low->velocity;
      a += low->acceleration;
      pv += low->path_velocity;
      ++under;
    }
    if (under > 0) {
      c.height = h / under;
      c.velocity = v / under;
      c.acceleration = a / under;
      c.path_velocity = pv / under;
    } else {
      c.height = m.scene.contact_wire_height;
      c.velocity = c.acceleration = c.path_velocity = 0.0;
    }
    for (const ContactPointMotion& cm : scratch) {
      c.on_wire.push_back(cm.on_wire);
      c.wire_height.push_back(cm.on_wire ? cm.height : 0.0);
      c.wire_velocity.push_back(cm.on_wire ? cm.velocity : 0.0);
      c.wire_acceleration.push_back(cm.on_wire ? cm.acceleration : 0.0);
      c.wire_path_velocity.push_back(cm.on_wire ? cm.path_velocity : 0.0);
      c.wire_force.push_back(cm.force);
    }
    c.applied_force = total_contact_force(m, s, static_cast<int>(p));
    out.pantographs.push_back(std::move(c));
  }
  return out;
}

bool all_finite(const ContactPointArray& msg) {
  auto ok = [](double x) { return std::isfinite(x); };
  if (!ok(msg.dt) || !ok(msg.speed) || !ok(msg.simulation_time) || !ok(msg.header.stamp.toSec())) return false;
  for (const ContactPoint& c : msg.pantographs) {
    for (double x : {c.position, c.height, c.velocity, c.acceleration, c.path_velocity, c.applied_force,
                     c.measurement_age})
      if (!ok(x)) return false;
    for (const auto* v : {&c.wire_height, &c.wire_velocity, &c.wire_acceleration, &c.wire_path_velocity, &c.wire_force})
      for (double x : *v)
        if (!ok(x)) return false;
  }
  return true;
}

}  // namespace ros_layer
}  // namespace catenary_sim
