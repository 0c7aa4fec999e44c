// Two pantographs 200 m apart on the reference catenary at 300 km/h: the trailing pantograph
// meets wires still vibrating from the leading one, so its contact force varies more (known
// physics of multiple-pantograph operation; e.g. Pombo & Ambrosio, and EN 50367's separate
// limits for trailing pantographs).
#include <gtest/gtest.h>

#include <cmath>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

TEST(MultiplePantographs, TrailingPantographVariesMoreThanTheLeadingOne) {
  Scene scene = load_scene_file(test_scenes::kReferenceTwoPantographs);
  scene.train_speed = 300.0 / 3.6;
  Simulation sim(scene);
  const Model& m = sim.model();
  ASSERT_EQ(m.pantographs.size(), 2u);
  PassRecorder rec(m);
  rec.record(m, sim.state());
  while (sim.step() == StepStatus::kOk) rec.record(m, sim.state());
  ASSERT_EQ(sim.state().status, StepStatus::kFinished) << sim.status_message();
  const auto stats = rec.statistics(m);
  const PantographStatistics& lead = stats[0];
  const PantographStatistics& trail = stats[1];
  ASSERT_EQ(lead.name, "leading");
  ASSERT_EQ(trail.name, "trailing");
  // Both cross most of the 880 m section: enough samples for stable statistics.
  EXPECT_GT(lead.samples, 5000u);
  EXPECT_GT(trail.samples, 5000u);
  EXPECT_GT(trail.filtered.std_dev, lead.filtered.std_dev);
  // Each pantograph's mean is still its static uplift within the roof-spring bound of
  // test_reference_pass (160 N/m x 0.05 m = 8 N).
  EXPECT_NEAR(lead.filtered.mean, 100.0, 8.0);
  EXPECT_NEAR(trail.filtered.mean, 100.0, 8.0);
}
