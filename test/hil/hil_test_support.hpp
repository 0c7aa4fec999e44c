// Helpers of the hardware-in-the-loop tests (test/hil, and test/ros/test_hil_loop.cpp): the
// reference scenes, the wire points of a frame, the loop replayed offline, and the 20 Hz
// statistics of a series over the analysis section.
#pragma once

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "catenary_sim/hil/loop.hpp"
#include "catenary_sim/hil/rig_pantograph.hpp"
#include "../support/scenes.hpp"

namespace hil_test {

using namespace catenary_sim;
using namespace catenary_sim::hil;

inline const std::string& kDir = test_scenes::kSourceDir;

inline Scene scene_with_dt(const std::string& file, double dt) {
  return test_scenes::edited_scene(file, [dt](YAML::Node& root) {
    if (dt > 0.0) root["numerics"]["dt"] = dt;
  });
}

inline const PantographSpec& lumped_spec(const Scene& lumped, const std::string& name) {
  for (const PantographSpec& ps : lumped.pantographs)
    if (ps.name == name) return ps;
  throw std::runtime_error("no pantograph " + name);
}

inline std::vector<WirePoint> wire_points(const PantographPoint& c) {
  std::vector<WirePoint> w(c.wires.size());
  for (std::size_t k = 0; k < w.size(); ++k) {
    w[k].on_wire = c.wires[k].on_wire;
    w[k].height = c.wires[k].on_wire ? c.wires[k].height : 0.0;
    w[k].path_velocity = c.wires[k].on_wire ? c.wires[k].path_velocity : 0.0;
  }
  return w;
}

// The contact point of each period: step, position and applied force of the first pantograph.
struct Series {
  std::vector<std::uint64_t> step;
  std::vector<double> x, f;
};

// What the rig sees of the first external pantograph after a period, in whatever frame the
// transport carries (the core's PointFrame, or the ROS ContactPointArray).
struct Observed {
  std::uint64_t step = 0;
  double speed = 0.0, position = 0.0, applied_force = 0.0;  // m/s, m, N
  std::vector<WirePoint> wire;
};

// The loop of the HIL nodes (config/reference_55m_hil.yaml, `dt`, `k` steps a period, the newest
// measurement held) and virtual_rig (the lumped pantograph of the same name in
// config/reference_55m.yaml, stepped up to each contact point against the previous one's wire
// extrapolated along its path velocity, answering with its contact force), period by period
// without a clock. `observe(model, state, k)` gives the contact point the transport carries. The
// force of period i is the rig's answer to the contact point of step `measurement_step[i]` (null:
// to the last one, no delay). Returns false with `error` set when a period names a step that was
// not sent before it.
template <class Observe>
bool replay(double dt, int k, const std::vector<std::uint64_t>* measurement_step, Series& out, std::string& error,
            Observe observe) {
  Simulation sim(scene_with_dt("reference_55m_hil.yaml", dt));
  const Model& m = sim.model();
  const std::vector<int> external = external_pantographs(m);
  if (external.size() != 1) {
    error = "reference_55m_hil.yaml has " + std::to_string(external.size()) + " external pantographs, 1 expected";
    return false;
  }
  const int p = external[0];
  const Scene lumped = load_scene_file(test_scenes::kReference);
  RigPantograph rig(lumped_spec(lumped, m.pantographs[p].name), lumped.contact.stiffness);
  Observed point = observe(m, sim.state(), k);
  rig.reset(point.wire, point.speed);
  std::map<std::uint64_t, double> answers{{point.step, rig.contact_force(point.wire)}};
  std::uint64_t rig_step = point.step;
  std::string err;
  for (std::size_t i = 0; !sim.finished(); ++i) {
    std::uint64_t used = rig_step;
    if (measurement_step) {
      if (i >= measurement_step->size()) {
        error = "the live pass had " + std::to_string(i) + " periods, the replay has more";
        return false;
      }
      used = (*measurement_step)[i];
    }
    const auto a = answers.find(used);
    if (a == answers.end()) {
      error = "period " + std::to_string(i) + " used the answer to step " + std::to_string(used) +
              ", which is not a contact point sent before it (last: " + std::to_string(rig_step) + ")";
      return false;
    }
    // As the node: the measurement goes through the core's check, is held and clamped.
    sim.set_external_force(p, a->second, &err);
    sim.set_external_force(p, std::clamp(sim.state().external_force[p], 0.0, Simulation::kMaxExternalForce), &err);
    for (int j = 0; j < k && !sim.finished(); ++j)
      if (sim.step() != StepStatus::kOk) {
        error = "the replay diverged: " + sim.status_message();
        return false;
      }
    const double speed = point.speed;
    const std::vector<WirePoint> wire = point.wire;
    point = observe(m, sim.state(), k);
    out.step.push_back(point.step);
    out.x.push_back(point.position);
    out.f.push_back(point.applied_force);
    // As virtual_rig on a contact point, then its answer.
    for (std::uint64_t s = rig_step; s < point.step; ++s)
      rig.step(dt, rig.contact_force(wire, static_cast<double>(s - rig_step) * dt), speed);
    rig_step = point.step;
    answers[rig_step] = rig.contact_force(point.wire);
  }
  return true;
}

// 20 Hz filtered statistics over the analysis section of a series sampled at `rate`.
inline ForceStatistics section_stats(const Model& m, const Series& s, double rate) {
  const double x0 = m.support_x[m.scene.analysis_first()], x1 = m.support_x[m.scene.analysis_last()];
  const std::vector<double> filtered = lowpass_zero_phase(s.f, rate, m.scene.output.filter_cutoff);
  std::vector<double> sec;
  for (std::size_t i = 0; i < s.f.size(); ++i)
    if (s.x[i] >= x0 && s.x[i] <= x1) sec.push_back(filtered[i]);
  return force_statistics(sec);
}

// The internal lumped pantograph of reference_55m.yaml, sampled once per period.
inline Series internal_series(double dt, int k) {
  Simulation internal(scene_with_dt("reference_55m.yaml", dt));
  const Model& m = internal.model();
  Series in;
  while (!internal.finished()) {
    for (int j = 0; j < k; ++j) internal.step();
    in.x.push_back(pantograph_position(m, internal.state(), 0));
    in.f.push_back(total_contact_force(m, internal.state(), 0));
  }
  return in;
}

}  // namespace hil_test
