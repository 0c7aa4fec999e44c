// The endless line (line.endless): a block of equal spans under the moving window, moved back a
// span at a time as the train runs on. Because the block is periodic where the window goes, the
// move is exact: the pass must be the same computation as on a long finite line far from its
// anchors, and a line of any length costs the same per simulated second.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "../support/scene_refusal.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

namespace {

const std::string& kEndless = test_scenes::kReferenceEndless;
const std::string& kFinite = test_scenes::kReference;

}  // namespace

class EndlessLineDamping : public ::testing::TestWithParam<const char*> {};

TEST_P(EndlessLineDamping, MovingTheBlockBackIsExact) {
  // The same 20 spans of pass, from station 1650 m (span 30), on the endless line and on a finite
  // 60-span line whose anchors the window never reaches (it reaches at most 7 spans ahead and 6
  // behind). Both integrate the same window over spans whose data agree to rounding, so the
  // contact force must agree to rounding at every step: 1e-4 N, a millionth of the force (the two
  // models differ in size, so their static solves and window factors round differently, and
  // that is carried over 8500 steps), while an error in the move (a node off by one, a lost
  // velocity or acceleration) changes the force by newtons. With the half-step damping and with
  // the centred step, whose window factors are rebuilt after each move.
  const std::vector<std::string> pass = {"train.start=1650", "train.end=2750", "numerics.preset=balanced",
                                         std::string("numerics.damping=") + GetParam()};
  std::vector<std::string> endless = pass, finite = pass;
  finite.insert(finite.end(), {"line.span_count=60", "numerics.window=auto"});
  Simulation a(load_scene_file(kEndless, endless)), b(load_scene_file(kFinite, finite));
  ASSERT_TRUE(a.model().endless);
  ASSERT_LT(a.model().scene.spans.size(), 30u);  // a block, not a line
  EXPECT_NEAR(pantograph_position(a.model(), a.state(), 0), pantograph_position(b.model(), b.state(), 0), 1e-9);
  double worst = 0.0, offset_seen = 0.0;
  while (true) {
    const StepStatus sa = a.step(), sb = b.step();
    ASSERT_EQ(sa, sb) << a.status_message() << " / " << b.status_message();
    if (sa != StepStatus::kOk) break;
    worst = std::max(worst, std::fabs(total_contact_force(a.model(), a.state(), 0) - total_contact_force(b.model(), b.state(), 0)));
    ASSERT_NEAR(pantograph_position(a.model(), a.state(), 0), pantograph_position(b.model(), b.state(), 0), 1e-6);
    offset_seen = a.state().line_offset;
  }
  EXPECT_NEAR(a.state().time, 1100.0 / (300 / 3.6), 0.01);  // the whole 20 spans
  // The block was moved along (20 spans run, the block holds fewer).
  EXPECT_GT(offset_seen - a.model().initial_line_offset, 15 * 55.0);
  EXPECT_LT(worst, 1e-4);
}

INSTANTIATE_TEST_SUITE_P(Damping, EndlessLineDamping, ::testing::Values("half_step", "centred"));

TEST(EndlessLine, SceneErrorsNameTheField) {
  auto message = [](const std::vector<std::string>& ov) { return test_scenes::refusal_of(kEndless, ov); };
  // Only the window around the train is modelled: no window, no endless line.
  EXPECT_NE(message({"numerics.window=off"}).find("numerics.window"), std::string::npos);
  EXPECT_NE(message({"line.span_count=10"}).find("line.span_count"), std::string::npos);
  EXPECT_NE(message({"train.end=-100"}).find("train.end"), std::string::npos);
  // The window is explicit only.
  EXPECT_NE(message({"numerics.integrator=implicit"}).find("numerics.integrator"), std::string::npos);
}
