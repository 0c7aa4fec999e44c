// Contact across an overlap with a twin contact wire: a head with two collector strips at the
// crossing point touches four wires at once (two contact wires of each series, eq. 15-16), and
// the design geometry of eq. 6-8 puts the two series at the same height at mid-transition.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <set>
#include <sstream>

#include "catenary_sim/core/simulation.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

namespace {

// calpe_example with a twin contact wire in both series and a two-strip head, pressed on at x.
Scene twin_overlap(double x) {
  return test_scenes::edited_scene("calpe_example.yaml", [x](YAML::Node& root) {
    for (YAML::Node sec : root["sections"]) sec["contact_wire_count"] = 2;
    YAML::Node strips;
    for (double off : {-0.25, 0.25}) {
      YAML::Node c;
      c["offset"] = off;
      strips.push_back(c);
    }
    root["pantographs"][0]["collectors"] = strips;
    root["train"]["start"] = x;
  });
}

}  // namespace

TEST(OverlapContacts, TwoStripsOnATwinOverlapTouchFourWiresAtTheCrossing) {
  Simulation sim(twin_overlap(50.0));
  const Model& m = sim.model();
  ASSERT_EQ(m.contact_wires.size(), 4u);
  ASSERT_EQ(m.collectors.size(), 2u);
  const State& s = sim.state();  // eq. 23 with the head at the crossing point Q
  std::set<int> touched;
  double total = 0.0;
  for (int c = 0; c < static_cast<int>(m.collectors.size()); ++c)
    for (int w = 0; w < static_cast<int>(m.contact_wires.size()); ++w) {
      const double f = s.contact_force_on(m, c, w);
      EXPECT_GE(f, 0.0);
      if (f > 0.0) touched.insert(static_cast<int>(w));
      total += f;
    }
  EXPECT_EQ(touched.size(), 4u);
  EXPECT_NEAR(total, 120.0, 1e-6);  // the static thrust, shared among all contacts
  // By eq. 8 the two series cross at mid-span: equal design heights at Q (to the EI correction of
  // the parabola, well under a millimetre).
  const Wire& w1 = m.wires[m.contact_wires[0]];
  const Wire& w2 = m.wires[m.contact_wires[2]];
  ASSERT_NE(w1.section, w2.section);
  auto height_at = [](const Wire& w, double x) {
    const int e = w.element_at(x);
    const double t = (x - w.x[e]) / (w.x[e + 1] - w.x[e]);
    return (1 - t) * w.height[e] + t * w.height[e + 1];
  };
  EXPECT_NEAR(height_at(w1, 50.0), height_at(w2, 50.0), 1e-3);
}

TEST(OverlapContacts, AwayFromTheOverlapOnlyOneSeriesIsTouched) {
  for (double x : {30.0, 70.0}) {
    Simulation sim(twin_overlap(x));
    const Model& m = sim.model();
    for (int c = 0; c < static_cast<int>(m.collectors.size()); ++c)
      for (int w = 0; w < static_cast<int>(m.contact_wires.size()); ++w) {
        const int section = m.wires[m.contact_wires[w]].section;
        const double f = sim.state().contact_force_on(m, c, w);
        if (section == (x < 50.0 ? 0 : 1)) {
          EXPECT_GT(f, 0.0) << "x " << x << " wire " << w;
        } else {
          EXPECT_EQ(f, 0.0) << "x " << x << " wire " << w;
        }
      }
  }
}
