// The step of a 3-D line moves both of its planes whoever calls it: the free step() on a copy of a
// Simulation's state gives Simulation::step's lateral and vertical state, and make_state gives a
// 3-D line's state its lateral plane.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "catenary_sim/core/engine/lateral_step.hpp"
#include "catenary_sim/core/simulation.hpp"

using namespace catenary_sim;

namespace {

Scene gusty_line(const std::vector<std::string>& extra) {
  std::vector<std::string> ov = {"numerics.preset=fast", "line.span_count=4"};
  ov.insert(ov.end(), extra.begin(), extra.end());
  return load_scene_file(CATENARY_SIM_SOURCE_DIR "/config/reference_55m_3d.yaml", ov);
}

}  // namespace

TEST(StepBothPlanes, FreeStepMovesTheLateralPlaneAsSimulationStep) {
  // The same operations on the same values in the same order: equal to the bit, no tolerance.
  // Without the window both planes' sweeps run together (the joint sweep); with it, one after the
  // other: both paths.
  for (const std::string window : {"", "numerics.window=auto"}) {
    Simulation sim(gusty_line(window.empty() ? std::vector<std::string>{} : std::vector<std::string>{window}));
    const Model& m = sim.model();
    ASSERT_TRUE(m.lateral);
    State s = sim.state();
    for (int k = 0; k < 400; ++k) {
      ASSERT_EQ(sim.step(), StepStatus::kOk);
      ASSERT_EQ(step(m, s), StepStatus::kOk);
    }
    const State& r = sim.state();
    // The lateral plane moved in the gusts (else the comparison below could not fail).
    double moved = 0.0;
    for (int i = 0; i < m.lateral->n; ++i) moved = std::max(moved, std::fabs(r.lateral.y[i] - m.lateral->initial[i]));
    EXPECT_GT(moved, 0.0) << window;
    ASSERT_EQ(s.lateral.y.size(), r.lateral.y.size());
    int differ = 0;
    for (int i = 0; i < m.lateral->n; ++i)
      differ += s.lateral.y[i] != r.lateral.y[i] || s.lateral.v[i] != r.lateral.v[i];
    EXPECT_EQ(differ, 0) << window << ": lateral nodes off Simulation::step's";
    int differ_u = 0;
    for (int i = 0; i < m.n_dof; ++i) differ_u += s.u[i] != r.u[i] || s.v[i] != r.v[i];
    EXPECT_EQ(differ_u, 0) << window << ": vertical DOFs off Simulation::step's";
    EXPECT_EQ(s.time, r.time);
    EXPECT_EQ(s.lateral.collector_lateral, r.lateral.collector_lateral);
  }
}

TEST(StepBothPlanes, MakeStateGivesTheLateralPlane) {
  Simulation sim(gusty_line({}));
  const Model& m = sim.model();
  ASSERT_TRUE(m.lateral);
  const State s = make_state(m);
  ASSERT_EQ(s.lateral.y.size(), static_cast<Eigen::Index>(m.lateral->n));
  for (int i = 0; i < m.lateral->n; ++i) EXPECT_EQ(s.lateral.y[i], m.lateral->initial[i]);  // the pass starts here
  EXPECT_EQ(s.lateral.dropper_stretch.size(), m.droppers.size());
}
