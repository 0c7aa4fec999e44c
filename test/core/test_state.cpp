// A State is copied by skins that snapshot and restore a pass. The step keeps buffers and caches
// across steps (the explicit step swaps its new displacements in, the centred damping step keeps
// the load in its force buffer, the implicit one its slack droppers' solves): a copy must carry
// its own, so that it steps exactly as its original and neither disturbs the other. Stepping a
// copy and its original in turn would mix their steps if they shared any of it.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "../support/scenes.hpp"

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

// The lateral plane of a 3-D line as expect_same the vertical one: its displacements and
// velocities, the droppers' lean the next vertical step takes, the wind held between refreshes,
// the window's placement and the contact points on the strips. False at the first difference.
bool same_lateral(const State& a, const State& b, std::string* what) {
  const LateralState &x = a.lateral, &y = b.lateral;
  auto differs = [what](bool d, const char* name) {
    if (d && what->empty()) *what = name;
    return d;
  };
  bool d = false;
  d |= differs(a.u != b.u || a.v != b.v, "u, v");
  d |= differs(x.y != y.y || x.v != y.v, "lateral y, v");
  d |= differs(x.dropper_stretch != y.dropper_stretch, "dropper_stretch");
  d |= differs(x.registration_travel != y.registration_travel, "registration_travel");
  d |= differs(x.registration_force != y.registration_force, "registration_force");
  d |= differs(x.wind_speed != y.wind_speed || x.wind_points != y.wind_points, "wind_speed, wind_points");
  d |= differs(x.next_wind_update != y.next_wind_update || x.wind_time != y.wind_time, "wind refresh times");
  d |= differs(x.window_first_support != y.window_first_support || x.window_last_support != y.window_last_support,
               "window supports");
  for (std::size_t w = 0; w < x.window.size() && w < y.window.size(); ++w)
    d |= differs(x.window[w].lo != y.window[w].lo || x.window[w].hi != y.window[w].hi, "window nodes");
  d |= differs(x.lead_y != y.lead_y || x.lead_v != y.lead_v || x.lead_y_before != y.lead_y_before ||
                   x.lead_v_before != y.lead_v_before || x.lead_time != y.lead_time,
               "gust lead");
  // (NaN where a collector is off the wires: compared as bits)
  d |= differs(x.collector_lateral.size() != y.collector_lateral.size() ||
                   std::memcmp(x.collector_lateral.data(), y.collector_lateral.data(),
                               sizeof(double) * x.collector_lateral.size()) != 0,
               "collector_lateral");
  d |= differs(x.collector_wire != y.collector_wire, "collector_wire");
  d |= differs(a.head_wind != b.head_wind || a.contact_force != b.contact_force, "head_wind, contact_force");
  return !d;
}

class ThreeDimensionalStateCopy : public ::testing::TestWithParam<const char*> {};

TEST_P(ThreeDimensionalStateCopy, InTurbulentWindStepsAsItsOriginal) {
  // The endless line in a turbulent cross wind, staggered and swaying: both planes windowed, the
  // block moved back and the field generated ahead while the copies step, the wind refreshed
  // every few steps. The lateral plane's state must travel with a copy and its workspace (the
  // window's lists and cut forces, the fused or centred step's buffers and window factors) be the
  // copy's own. With either damping step.
  const Scene scene = load_scene_file(
      test_scenes::kReferenceEndless,
      {"numerics.preset=balanced", "stagger.contact_wire=[0.3,-0.3]", "stagger.messenger=[0.0]", "wind.speed=20",
       "wind.turbulence.intensity=0.15", "wind.turbulence.seed=3", "pantograph_head.sway.amplitude=0.03",
       "pantograph_head.sway.frequency=0.8", std::string("numerics.damping=") + GetParam()});
  Simulation sim(scene);
  const Model& m = sim.model();
  ASSERT_TRUE(m.lateral && m.lateral->windowed && !m.lateral->field.empty());
  for (int k = 0; k < 300; ++k) ASSERT_EQ(sim.step(), StepStatus::kOk);
  const State original = sim.state();
  State copied(original);
  State assigned = make_state(m);
  assigned = original;
  // Each of these copies lacks one part of the lateral state (what a copy that dropped it would
  // carry: a fresh state's value), so that this test is seen to fail if a copy loses it.
  const State fresh = make_state(m);
  std::vector<std::pair<std::string, State>> dropped;
  auto drop = [&](const std::string& name, auto&& clear) {
    State d(original);
    clear(d);
    dropped.emplace_back(name, std::move(d));
  };
  drop("y", [&](State& d) { d.lateral.y = fresh.lateral.y; });
  drop("lateral v", [&](State& d) { d.lateral.v = fresh.lateral.v; });
  drop("dropper_stretch", [&](State& d) { d.lateral.dropper_stretch = fresh.lateral.dropper_stretch; });
  drop("wind_speed", [&](State& d) { d.lateral.wind_speed = fresh.lateral.wind_speed; });
  drop("next_wind_update", [&](State& d) { d.lateral.next_wind_update = fresh.lateral.next_wind_update; });
  ASSERT_GT(m.lateral->lead_every, 0);  // the gust lead stepped on its own: its state travels too
  drop("lead_y", [&](State& d) { d.lateral.lead_y = fresh.lateral.lead_y; });
  drop("lead_v", [&](State& d) { d.lateral.lead_v = fresh.lateral.lead_v; });
  drop("lead_y_before", [&](State& d) { d.lateral.lead_y_before = fresh.lateral.lead_y_before; });
  drop("lead_time", [&](State& d) { d.lateral.lead_time = fresh.lateral.lead_time; });
  State reference(original);
  const double offset = original.line_offset;
  const int first_support = original.lateral.window_first_support;
  bool window_moved = false;
  for (int k = 0; k < 3000; ++k) {
    ASSERT_EQ(step(m, reference), StepStatus::kOk);
    ASSERT_EQ(step(m, copied), StepStatus::kOk);
    ASSERT_EQ(step(m, assigned), StepStatus::kOk);
    for (auto& [name, d] : dropped) step(m, d);
    window_moved |= reference.lateral.window_first_support != first_support;
  }
  ASSERT_GT(reference.line_offset, offset);  // the block moved back in the steps compared
  ASSERT_TRUE(window_moved);                 // and the window moved on
  std::string what;
  EXPECT_TRUE(same_lateral(reference, copied, &what)) << "copy-constructed: " << what;
  expect_same(reference, copied, "copy-constructed");
  what.clear();
  EXPECT_TRUE(same_lateral(reference, assigned, &what)) << "copy-assigned: " << what;
  expect_same(reference, assigned, "copy-assigned");
  for (auto& [name, d] : dropped) {
    what.clear();
    EXPECT_FALSE(same_lateral(reference, d, &what)) << "a copy without " << name << " stepped as its original";
  }
  for (int k = 0; k < 3000; ++k) ASSERT_EQ(sim.step(), StepStatus::kOk);
  what.clear();
  EXPECT_TRUE(same_lateral(sim.state(), reference, &what)) << "the simulation's own: " << what;
}

INSTANTIATE_TEST_SUITE_P(Damping, ThreeDimensionalStateCopy, ::testing::Values("half_step", "centred"));

INSTANTIATE_TEST_SUITE_P(Integrators, StateCopy,
                         ::testing::Values(std::vector<std::string>{},
                                           std::vector<std::string>{"numerics.damping=centred"},
                                           std::vector<std::string>{"numerics.damping=centred", "numerics.window=auto"},
                                           std::vector<std::string>{"numerics.integrator=implicit"}));

}  // namespace
