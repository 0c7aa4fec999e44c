// The divergence watchdog: a NaN or a displacement beyond numerics.divergence_limit stops the
// run with a message naming where, and nothing after it is computed or passed on.
#include <gtest/gtest.h>

#include <cmath>

#include "catenary_sim/core/simulation.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

TEST(Watchdog, RunawayDisplacementStopsTheRun) {
  // The head starts 2 mm up (at the anchor) and rises by centimetres mid-span under 100 N, so a
  // 10 mm limit must trip within the pass.
  Simulation sim(load_scene_file(test_scenes::kReference, {"numerics.divergence_limit=0.01"}));
  StepStatus st = StepStatus::kOk;
  int n = 0;
  while (st == StepStatus::kOk && n < 100000) {
    st = sim.step();
    ++n;
  }
  ASSERT_EQ(st, StepStatus::kDiverged);
  const std::string msg = sim.status_message();
  EXPECT_NE(msg.find("diverged at t = "), std::string::npos) << msg;
  EXPECT_NE(msg.find("limit 0.01 m"), std::string::npos) << msg;
  // The message gives the value the rejected step reached, beyond the limit (not the last good
  // step's, which is within it).
  const double reached = sim.state().diverged_displacement;
  EXPECT_GT(std::fabs(reached), 0.01);
  const std::size_t at = msg.find("reached ");
  ASSERT_NE(at, std::string::npos) << msg;
  EXPECT_GT(std::fabs(std::stod(msg.substr(at + 8))), 0.01) << msg;
  // The state keeps the last good step: nothing beyond the limit is passed on.
  EXPECT_LE(sim.state().u.cwiseAbs().maxCoeff(), 0.01);
  const double t = sim.state().time;
  EXPECT_EQ(sim.step(), StepStatus::kDiverged);  // refuses to go on
  EXPECT_EQ(sim.state().time, t);
}

TEST(Watchdog, NaNIsCaughtOnTheStepItAppears) {
  Simulation sim(load_scene_file(test_scenes::kReference));
  State s = sim.state();
  s.wire_uplift(sim.model(), 0, sim.model().wires[0].nodes() / 2) = std::nan("");
  EXPECT_EQ(step(sim.model(), s), StepStatus::kDiverged);
  EXPECT_EQ(s.time, sim.state().time);  // time did not advance past the bad step
  EXPECT_GE(s.diverged_dof, 0);
}

// A NaN in the lateral plane of a 3-D line stops the run at the lateral step it appears in, and
// the lateral state keeps its last good values (nothing diverged is passed on), whichever
// lateral step the numerics take: the fused sweep (the default), the centred damping step, and
// the generic step of an implicit vertical plane or of rotations as DOFs.
TEST(Watchdog, LateralNaNLeavesTheLastGoodLateralState) {
  for (const std::vector<std::string>& numerics :
       {std::vector<std::string>{}, {"numerics.damping=centred"}, {"numerics.integrator=implicit"},
        {"numerics.rotary_inertia=lumped"}}) {
    std::vector<std::string> o{"line.span_count=4", "stagger.contact_wire=[0.3,-0.3]", "wind.speed=20"};
    o.insert(o.end(), numerics.begin(), numerics.end());
    Simulation sim(load_scene_file(test_scenes::kReference, o));
    const Model& m = sim.model();
    ASSERT_TRUE(m.lateral);
    State s = sim.state();
    const int node = m.lateral->wires[0].w_dof + m.lateral->wires[0].nodes() * 3 / 8;  // mid-span
    ASSERT_GT(m.lateral->inv_mass[node], 0.0);
    s.lateral.v[node] = std::nan("");
    const Eigen::VectorXd y_before = s.lateral.y;
    EXPECT_EQ(step(m, s), StepStatus::kDiverged) << numerics.size();
    EXPECT_TRUE(s.lateral.diverged);
    EXPECT_TRUE(s.lateral.y.allFinite()) << (numerics.empty() ? "fused" : numerics[0]);
    EXPECT_TRUE(s.lateral.y == y_before) << (numerics.empty() ? "fused" : numerics[0]);
    // The message names where, and the value the rejected substep gave.
    // (a solve along the wire spreads the NaN over it: the first DOF beyond is the wire's first
    // stepped one or the NaN's own)
    EXPECT_GE(s.lateral.diverged_node, m.lateral->wires[0].w_dof);
    EXPECT_LE(s.lateral.diverged_node, node);
    EXPECT_TRUE(std::isnan(s.lateral.diverged_position));
  }
  // Through Simulation: a lateral limit inside the stagger (+-0.3 m) stops the first step, and the
  // message names the contact wire at a support and a position beyond the limit.
  Simulation sim(load_scene_file(test_scenes::kReference, {"line.span_count=4", "stagger.contact_wire=[0.3,-0.3]",
                                                           "numerics.divergence_limit=0.2"}));
  EXPECT_EQ(sim.step(), StepStatus::kDiverged);
  const std::string msg = sim.status_message();
  EXPECT_NE(msg.find("lateral position of contact_wire at x = "), std::string::npos) << msg;
  EXPECT_NE(msg.find("below the line's own lateral positions"), std::string::npos) << msg;
  EXPECT_GT(std::fabs(sim.state().lateral.diverged_position), 0.2) << msg;
}
