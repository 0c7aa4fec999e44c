// The State's accessors read the results in the railway's words (a collector's force on a
// contact wire, a wire node's height, a pantograph mass's displacement): checked here against
// the physics they report, not against the flat layouts behind them.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "catenary_sim/core/simulation.hpp"

using namespace catenary_sim;

namespace {

Simulation load(const std::string& file, const std::vector<std::string>& overrides = {}) {
  return Simulation(load_scene_file(std::string(CATENARY_SIM_SOURCE_DIR) + "/config/" + file, overrides));
}

// Eq. 12: the collector's wire height is the wire's node heights weighted over the rub length.
double weighted_wire_height(const Model& m, const State& s, int pantograph, int collector, int k) {
  const int wi = m.contact_wires[k];
  std::vector<int> node(m.max_contact_nodes);
  std::vector<double> weight(m.max_contact_nodes);
  const double xc = s.front - m.pantographs[pantograph].position + m.collectors[collector].offset;
  const int cnt = contact_weights(m.wires[wi], m.rub_length, xc, node.data(), weight.data());
  if (cnt == 0) return std::nan("");
  double y = 0.0;
  for (int a = 0; a < cnt; ++a) y += weight[a] * s.wire_height(m, wi, node[a]);
  return y;
}

// Eq. 22 for every collector and contact wire: in touch, k0 times the head's height above the
// wire under the collector; out of touch nothing. Relative 1e-9 of k0 x gap: the round-off of
// the heights (~5 m) against a gap of millimetres, times k0.
void expect_contact_law(const Model& m, const State& s, int p, const std::string& where) {
  const Pantograph& pg = m.pantographs[p];
  for (int ci : pg.collectors)
    for (std::size_t k = 0; k < m.contact_wires.size(); ++k) {
      const double f = s.contact_force_on(m, ci, static_cast<int>(k));
      const double y = s.wire_height_under(m, ci, static_cast<int>(k));
      EXPECT_GE(f, 0.0) << where;
      if (std::isnan(y)) {
        EXPECT_EQ(f, 0.0) << where << ": collector " << ci << " not under wire " << k;
        continue;
      }
      // The observed wire height is eq. 12 of the node heights read by wire_height (1e-12 m:
      // the same sum, at most reordered).
      EXPECT_NEAR(y, weighted_wire_height(m, s, p, ci, static_cast<int>(k)), 1e-12) << where;
      const double gap = pg.contact_reference(m.collectors[ci]) + s.u[m.collectors[ci].dof] - y;
      if (f > 0.0) {
        EXPECT_NEAR(f, m.contact_stiffness * gap, 1e-9 * m.contact_stiffness * std::fabs(gap) + 1e-12) << where;
      } else {
        EXPECT_LE(gap, 1e-12) << where << ": out of touch, the head is not above the wire";
      }
    }
}

// The thrust at the start (eq. 9: F0 + a v^2): the static uplift and the aerodynamic uplift on
// the frame and on every head at the train's speed.
double thrust(const Model& m, const State& s, int p) {
  double f = m.pantographs[p].static_uplift + frame_aero_uplift(m, s, p);
  for (int h = 0; h < head_count(m, p); ++h) f += head_aero_uplift(m, s, p, h);
  return f;
}

}  // namespace

// At the initial static state (eq. 23) the springs are referenced so that the contact force is
// the thrust F0 + a v^2 exactly (docs/model_and_numerics.md, Pantographs): the collectors' forces
// summed over the contact wires and the collectors give it back, to the statics' solve (1e-4 N,
// as InitialConfiguration.PantographPressedOnWithStaticUplift).
TEST(StateAccessors, StaticPassPressesWithTheStaticUplift) {
  Simulation sim = load("reference_55m.yaml");
  const Model& m = sim.model();
  const State& s = sim.state();
  const Pantograph& pg = m.pantographs.at(0);
  ASSERT_FALSE(pg.moving_force);
  double sum = 0.0;
  for (int ci : pg.collectors) {
    double over_wires = 0.0;
    for (std::size_t k = 0; k < m.contact_wires.size(); ++k) over_wires += s.contact_force_on(m, ci, static_cast<int>(k));
    EXPECT_EQ(s.collector_force(m, ci), over_wires);  // the same sum in the same order
    sum += s.collector_force(m, ci);
  }
  EXPECT_NEAR(sum, thrust(m, s, 0), 1e-4);
  EXPECT_NEAR(s.pantograph_force_on(m, 0, 0), thrust(m, s, 0), 1e-4);
  // Summed collector by collector and wire by wire as total_contact_force: to the bit.
  EXPECT_EQ(s.head_contact_force(m, 0, -1), total_contact_force(m, s, 0));
  expect_contact_law(m, s, 0, "static state");
  // The head is the chain's first mass: its height is its reference plus its displacement.
  EXPECT_EQ(pg.reference_height + s.pantograph_displacement(m, 0, 0), head_height(m, s, 0));
  // At rest: every mass still.
  for (int i = 0; i < pg.dof_count(); ++i) EXPECT_EQ(s.pantograph_velocity(m, 0, i), 0.0) << "mass " << i;
}

// A wire node's height is its design height plus its uplift; the rigid anchors at the line's
// ends do not move, and the static uplift lifts the contact wire under the head (pushed up) while
// a steady arm far from it stays at its design height (static uplift, 1e-9 m: nothing reaches
// it but the round-off of the statics' solve).
TEST(StateAccessors, WireHeightsAreDesignPlusUplift) {
  Simulation sim = load("reference_55m.yaml");
  const Model& m = sim.model();
  const State& s = sim.state();
  for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
    const Wire& w = m.wires[wi];
    const int last = w.nodes() - 1;
    EXPECT_EQ(s.wire_uplift(m, static_cast<int>(wi), 0), 0.0) << w.name;
    EXPECT_EQ(s.wire_uplift(m, static_cast<int>(wi), last), 0.0) << w.name;
    for (int i = 0; i < w.nodes(); i += 17)
      EXPECT_EQ(s.wire_height(m, static_cast<int>(wi), i), w.height[i] + s.wire_uplift(m, static_cast<int>(wi), i));
  }
  const int ci = m.pantographs[0].collectors[0];
  State design = s;
  design.u.setZero();
  EXPECT_GT(s.wire_height_under(m, ci, 0), weighted_wire_height(m, design, 0, ci, 0))
      << "the uplift lifts the contact wire under the head";
  const double x_head = pantograph_position(m, s, 0);
  int far = -1;
  for (std::size_t k = 0; k < m.springs.size(); ++k)
    if (m.springs[k].steady_arm && std::fabs(m.springs[k].x - x_head) > 3.0 * m.longest_span) far = static_cast<int>(k);
  ASSERT_GE(far, 0);
  EXPECT_NEAR(s.support_uplift(m, far), 0.0, 1e-9);
}

// In an overlap (config/calpe_example.yaml at 50 m) the collectors touch both contact wires: a
// collector's force is the sum of its forces on each, the pantograph's the sum over the wires
// (1e-9 relative: the same terms summed in another order), and eq. 22 holds on each wire on its
// own, step after step.
TEST(StateAccessors, OverlapSplitsTheForceBetweenTheContactWires) {
  Simulation sim = load("calpe_example.yaml");
  const Model& m = sim.model();
  ASSERT_EQ(m.contact_wires.size(), 2u);
  while (pantograph_position(m, sim.state(), 0) < 50.0) ASSERT_EQ(sim.step(), StepStatus::kOk);
  int both = 0;
  for (int n = 0; n < 200; ++n) {
    ASSERT_EQ(sim.step(), StepStatus::kOk);
    const State& s = sim.state();
    const std::string where = "t = " + std::to_string(s.time);
    const double total = total_contact_force(m, s, 0);
    EXPECT_NEAR(s.pantograph_force_on(m, 0, 0) + s.pantograph_force_on(m, 0, 1), total, 1e-9 * total) << where;
    for (int ci : m.pantographs[0].collectors) {
      const double f0 = s.contact_force_on(m, ci, 0), f1 = s.contact_force_on(m, ci, 1);
      EXPECT_EQ(s.collector_force(m, ci), f0 + f1) << where;
      both += f0 > 0.0 && f1 > 0.0;
    }
    expect_contact_law(m, s, 0, where);
  }
  EXPECT_GT(both, 0) << "at 50 m the collectors touch both wires";
}

// Two heads, each on its own suspension (config/reference_55m_two_heads.yaml): a head's height
// is its reference plus its own mass's displacement (the pantograph's masses after the chain's),
// and the heads' forces add up to the pantograph's; statically that is the thrust, the static
// uplift and every aerodynamic uplift (1e-4 N, the statics' solve).
TEST(StateAccessors, EachHeadCarriesItsShareOfTheUplift) {
  Simulation sim = load("reference_55m_two_heads.yaml");
  const Model& m = sim.model();
  const State& s = sim.state();
  const Pantograph& pg = m.pantographs.at(0);
  ASSERT_EQ(pg.heads.size(), 2u);
  double heads = 0.0;
  for (int h = 0; h < 2; ++h) {
    EXPECT_EQ(head_height(m, s, 0, h), pg.heads[h].reference_height + s.pantograph_displacement(m, 0, pg.masses_count() + h));
    EXPECT_GT(s.head_contact_force(m, 0, h), 0.0) << "head " << h;
    heads += s.head_contact_force(m, 0, h);
  }
  EXPECT_NEAR(heads, thrust(m, s, 0), 1e-4);
  EXPECT_NEAR(heads, total_contact_force(m, s, 0), 1e-9 * heads);
  expect_contact_law(m, s, 0, "two heads, static state");
}
