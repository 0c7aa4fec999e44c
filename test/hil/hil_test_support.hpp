// Helpers of the ROS-free hardware-in-the-loop tests (test/hil): the reference scenes, the wire
// points of a frame, and the 20 Hz statistics of a series over the analysis section.
#pragma once

#include <yaml-cpp/yaml.h>

#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/statistics.hpp"
#include "catenary_sim/hil/loop.hpp"
#include "catenary_sim/hil/rig_pantograph.hpp"

namespace hil_test {

using namespace catenary_sim;
using namespace catenary_sim::hil;

inline const std::string kDir = CATENARY_SIM_SOURCE_DIR;

inline Scene scene_with_dt(const std::string& file, double dt) {
  YAML::Node root = YAML::LoadFile(kDir + "/config/" + file);
  if (dt > 0.0) root["numerics"]["dt"] = dt;
  std::stringstream yaml;
  yaml << root;
  return load_scene_string(yaml.str());
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

struct Series {
  std::vector<std::uint64_t> step;
  std::vector<double> x, f;
};

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
