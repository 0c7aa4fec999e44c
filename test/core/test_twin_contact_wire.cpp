// A twin contact wire (DC lines): two identical contact wires hanging from the same droppers.
// Symmetry fixes the answers: the two wires share every load equally, and two wires under the
// same messenger are stiffer than one.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <sstream>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/model/statics.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

namespace {

// The reference catenary on 4 spans, as one section with `count` contact wires.
Scene reference_with_contact_wires(int count) {
  return test_scenes::reference_with_contact_wires(count, 4, [](YAML::Node& root) { root["train"]["speed_kmh"] = 250.0; });
}

}  // namespace

TEST(TwinContactWire, BothWiresShareTheLoadEquallyAndTheLineIsStiffer) {
  const Scene twin = reference_with_contact_wires(2), single = reference_with_contact_wires(1);
  Simulation sim(twin);
  const Model& m = sim.model();
  ASSERT_EQ(m.contact_wires.size(), 2u);
  const Wire& a = m.wires[m.contact_wires[0]];
  const Wire& b = m.wires[m.contact_wires[1]];
  // Same design shape: the presag is set on each wire by its own droppers.
  for (int i = 0; i < a.nodes(); ++i) ASSERT_NEAR(a.height[i], b.height[i], 1e-12);
  // Static contact (eq. 23): the uplift splits in two equal halves.
  const State& s0 = sim.state();
  EXPECT_NEAR(s0.contact_force_on(m, 0, 0) + s0.contact_force_on(m, 0, 1), 100.0, 1e-6);
  EXPECT_NEAR(s0.contact_force_on(m, 0, 0), s0.contact_force_on(m, 0, 1), 1e-9);
  // During a pass too, at every step (rounding only: the two wires see identical operations).
  while (sim.step() == StepStatus::kOk) {
    const State& s = sim.state();
    const double f0 = s.contact_force_on(m, 0, 0), f1 = s.contact_force_on(m, 0, 1);
    ASSERT_NEAR(f0, f1, 1e-9 * (1.0 + f0)) << "t = " << s.time;
  }
  EXPECT_EQ(sim.state().status, StepStatus::kFinished);
  // Elasticity at mid-span of span 1: two contact wires (twice the contact-wire tension and
  // weight under the same messenger) rise less under the same force than one.
  const double x = 55.0 + 27.5;
  const double up_twin = ElasticityProbe(twin, 100.0).uplift(x)[0];
  const double up_single = ElasticityProbe(single, 100.0).uplift(x)[0];
  EXPECT_GT(up_single, 0.0);
  EXPECT_LT(up_twin, up_single);
}
