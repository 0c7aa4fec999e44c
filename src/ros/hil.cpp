#include "catenary_sim/ros/hil.hpp"
#include "catenary_sim/ros/params.hpp"

#include <cmath>

namespace catenary_sim {
namespace ros_layer {

HilTiming hil_timing(double rate, std::optional<double> scene_dt, double auto_dt) {
  try {
    return hil::hil_timing(rate, scene_dt, auto_dt, "parameter ~hil/rate", "~scene");
  } catch (const hil::HilError& e) {
    throw ParamError(e.what());
  }
}

ContactPointArray to_contact_points(const Model& m, const hil::PointFrame& f, const ros::Time& stamp,
                                    const std::string& frame) {
  ContactPointArray out;
  out.header.stamp = stamp;
  out.header.frame_id = frame;
  out.simulation_time = f.simulation_time;
  out.step = f.step;
  out.dt = f.dt;
  out.steps_per_period = f.steps_per_period;
  out.speed = f.speed;
  out.mode = static_cast<std::uint8_t>(f.mode);  // (the same codes: ContactPointArray.msg)
  out.pass_count = f.pass_count;
  out.measurement_step = f.measurement_step;
  for (int wi : m.contact_wires) out.contact_wires.push_back(m.wires[wi].name);
  for (const hil::PantographPoint& p : f.pantographs) {
    ContactPoint c;
    c.name = p.name;
    c.position = p.position;
    c.height = p.height;
    c.velocity = p.velocity;
    c.acceleration = p.acceleration;
    c.path_velocity = p.path_velocity;
    c.applied_force = p.applied_force;
    c.measurement_age = p.measurement_age;
    for (const ContactPointMotion& cm : p.wires) {
      c.on_wire.push_back(cm.on_wire);
      c.wire_height.push_back(cm.on_wire ? cm.height : 0.0);
      c.wire_velocity.push_back(cm.on_wire ? cm.velocity : 0.0);
      c.wire_acceleration.push_back(cm.on_wire ? cm.acceleration : 0.0);
      c.wire_path_velocity.push_back(cm.on_wire ? cm.path_velocity : 0.0);
      c.wire_force.push_back(cm.force);
    }
    out.pantographs.push_back(std::move(c));
  }
  return out;
}

ContactPointArray to_contact_points(const Model& m, const State& s, const ros::Time& stamp, const std::string& frame,
                                    int steps_per_period, std::vector<ContactPointMotion>& /*scratch*/) {
  hil::PointFrame f;
  hil::compute_frame(m, s, steps_per_period, f);
  return to_contact_points(m, f, stamp, frame);
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
