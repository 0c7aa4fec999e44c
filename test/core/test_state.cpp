// A State is copied by skins that snapshot and restore a pass. The step keeps buffers and caches
// across steps (the explicit step swaps its new displacements in, the centred damping step keeps
// the load in its force buffer, the implicit one its slack droppers' solves): a copy must carry
// its own, so that it steps exactly as its original and neither disturbs the other. Stepping a
// copy and its original in turn would mix their steps if they shared any of it.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "catenary_sim/core/simulation.hpp"

using namespace catenary_sim;

namespace {

// Two states that started equal and took the same steps: equal to the bit (same operations on
// the same numbers), so no tolerance.
void expect_same(const State& a, const State& b, const std::string& where) {
  ASSERT_EQ(a.status, StepStatus::kOk) << where;
  ASSERT_EQ(b.status, StepStatus::kOk) << where;
  EXPECT_EQ(a.time, b.time) << where;
  ASSERT_EQ(a.u.size(), b.u.size()) << where;
  for (Eigen::Index i = 0; i < a.u.size(); ++i) {
    ASSERT_EQ(a.u[i], b.u[i]) << where << ": u of DOF " << i;
    ASSERT_EQ(a.v[i], b.v[i]) << where << ": v of DOF " << i;
  }
  EXPECT_EQ(a.contact_force, b.contact_force) << where;
}

class StateCopy : public ::testing::TestWithParam<std::vector<std::string>> {};

TEST_P(StateCopy, StepsAsItsOriginalAndApart) {
  Simulation sim(load_scene_file(std::string(CATENARY_SIM_SOURCE_DIR) + "/config/reference_55m.yaml", GetParam()));
  const Model& m = sim.model();
  // Mid-pass, the pantograph in touch: the caches hold this pass's values.
  for (int k = 0; k < 300; ++k) ASSERT_EQ(sim.step(), StepStatus::kOk);
  State original = sim.state();
  State copied(original);
  State assigned = make_state(m);
  assigned = original;
  for (int k = 0; k < 300; ++k) {
    ASSERT_EQ(step(m, original), StepStatus::kOk);
    ASSERT_EQ(step(m, copied), StepStatus::kOk);
    ASSERT_EQ(step(m, assigned), StepStatus::kOk);
  }
  expect_same(original, copied, "copy-constructed");
  expect_same(original, assigned, "copy-assigned");
  // And the Simulation's own state, stepped alone the same 300 steps.
  for (int k = 0; k < 300; ++k) ASSERT_EQ(sim.step(), StepStatus::kOk);
  expect_same(sim.state(), original, "the simulation's own");
}

INSTANTIATE_TEST_SUITE_P(Integrators, StateCopy,
                         ::testing::Values(std::vector<std::string>{},
                                           std::vector<std::string>{"numerics.damping=centred"},
                                           std::vector<std::string>{"numerics.integrator=implicit"}));

}  // namespace
