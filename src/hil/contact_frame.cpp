#include "catenary_sim/hil/contact_frame.hpp"

#include <cmath>

#include "catenary_sim/core/simulation.hpp"

namespace catenary_sim {
namespace hil {

std::vector<int> external_pantographs(const Model& m) {
  std::vector<int> out;
  for (std::size_t p = 0; p < m.pantographs.size(); ++p)
    if (m.pantographs[p].external) out.push_back(static_cast<int>(p));
  return out;
}

const char* mode_name(Mode m) {
  switch (m) {
    case Mode::kWaiting: return "waiting";
    case Mode::kRunning: return "running";
    case Mode::kHold: return "safe hold";
    case Mode::kPaused: return "paused";
    case Mode::kEnded: return "ended";
  }
  return "ended";
}

void compute_frame(const Model& m, const State& s, int steps_per_period, PointFrame& out) {
  out.simulation_time = s.time;
  out.step = static_cast<std::uint64_t>(s.steps);
  out.dt = m.dt;
  out.steps_per_period = static_cast<std::uint32_t>(steps_per_period);
  out.speed = s.speed;
  out.mode = Mode::kRunning;
  out.measurement_step = 0;
  std::size_t n = 0;
  for (std::size_t p = 0; p < m.pantographs.size(); ++p)
    if (m.pantographs[p].external) ++n;
  out.pantographs.resize(n);
  std::size_t e = 0;
  for (std::size_t p = 0; p < m.pantographs.size(); ++p) {
    const Pantograph& pg = m.pantographs[p];
    if (!pg.external) continue;
    PantographPoint& c = out.pantographs[e++];
    if (c.name != pg.name) c.name = pg.name;
    c.position = pantograph_position(m, s, static_cast<int>(p));
    c.measurement_age = -1.0;
    contact_point_motion(m, s, static_cast<int>(p), c.wires);
    const std::size_t nw = m.contact_wires.size();
    // Per collector: the lowest contact wire under it (the one a force-driven collector pushes).
    double h = 0.0, v = 0.0, a = 0.0, pv = 0.0;
    int under = 0;
    for (std::size_t ci = 0; ci < pg.collectors.size(); ++ci) {
      const ContactPointMotion* low = nullptr;
      for (std::size_t k = 0; k < nw; ++k) {
        const ContactPointMotion& cm = motion_under(m, c.wires, ci, k);
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
    c.applied_force = total_contact_force(m, s, static_cast<int>(p));
  }
}

bool all_finite(const PointFrame& f) {
  auto ok = [](double x) { return std::isfinite(x); };
  if (!ok(f.dt) || !ok(f.speed) || !ok(f.simulation_time)) return false;
  for (const PantographPoint& c : f.pantographs) {
    for (double x : {c.position, c.height, c.velocity, c.acceleration, c.path_velocity, c.applied_force,
                     c.measurement_age})
      if (!ok(x)) return false;
    for (const ContactPointMotion& w : c.wires)
      if (w.on_wire && (!ok(w.height) || !ok(w.velocity) || !ok(w.acceleration) || !ok(w.path_velocity) ||
                        !ok(w.force)))
        return false;
  }
  return true;
}

}  // namespace hil
}  // namespace catenary_sim
