// A force moving slowly along a line against the statics: the contact wire's uplift under it at a
// row of stations against the static elasticity probe's there (gtest). Header-only.
#pragma once

#include <gtest/gtest.h>

#include <vector>

#include "catenary_sim/core/model/contact_geometry.hpp"
#include "catenary_sim/core/model/statics.hpp"
#include "catenary_sim/core/simulation.hpp"

namespace test_scenes {

// Steps `scene` (its pantograph a moving force of `force` N) and, as its front reaches `first`,
// `first + every`, ... up to `last` (m), expects contact wire 0's uplift under the force within
// `tolerance` (relative) of the static uplift under `force` there. Returns the stations checked.
inline int expect_quasi_static(const catenary_sim::Scene& scene, double force, double first, double every, double last,
                               double tolerance) {
  namespace cs = catenary_sim;
  const cs::ElasticityProbe probe(scene, force);
  cs::Simulation sim(scene);
  const cs::Model& m = sim.model();
  const cs::Wire& wire = m.wires[m.contact_wires[0]];
  std::vector<int> node(m.max_contact_nodes);
  std::vector<double> weight(m.max_contact_nodes);
  int checked = 0;
  double next = first;
  while (!sim.finished() && next <= last) {
    if (sim.step() != cs::StepStatus::kOk) {
      ADD_FAILURE() << sim.status_message();
      return checked;
    }
    const cs::State& s = sim.state();
    if (s.front < next) continue;
    const int cnt = cs::contact_weights(wire, 0.0, s.front, node.data(), weight.data());
    double u = 0.0;
    for (int a = 0; a < cnt; ++a) u += weight[a] * s.wire_uplift(m, 0, node[a]);
    const double expected = probe.uplift(s.front).at(0);
    EXPECT_GT(expected, 0.0) << "x " << s.front;
    EXPECT_NEAR(u, expected, tolerance * expected) << "x " << s.front;
    ++checked;
    next += every;
  }
  return checked;
}

}  // namespace test_scenes
