// Stitched catenary (docs/stitched_catenary.md): a stitch wire clamped to the messenger on both
// sides of every intermediate support carries the first droppers. Its statics against a string
// network solved on its own, the limit of a short stitch wire, what the stitch wire is for
// (elasticity at the support, its uniformity over the span, the contact-force spread at speed),
// the design state's balance, and bad input.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "catenary_sim/core/model/build_model.hpp"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/model/model_memory.hpp"
#include "catenary_sim/core/model/statics.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "catenary_sim/core/output/zero_phase_filter.hpp"
#include "catenary_sim/core/scene/scene.hpp"
#include "catenary_sim/core/simulation.hpp"
#include "../support/design_equilibrium.hpp"
#include "../support/scene_refusal.hpp"
#include "../support/scenes.hpp"

namespace cs = catenary_sim;

namespace {

constexpr double kTc = 20000.0, kTm = 16000.0, kTs = 3500.0;

// Two spans of 20 m, rigid supports, every wire without bending stiffness (a string), droppers at
// 2 m and 18 m of each span and a stitch wire of 8 m around the middle support: its clamps at
// 16 m and 24 m, the droppers at 18 m and 22 m on it.
std::string network_yaml(double element) {
  std::ostringstream y;
  y << "name: network\nline: {span_length: 20.0, span_count: 2, encumbrance: 1.2}\n"
    << "contact_wire: {linear_mass: 1.35, tension: " << kTc << "}\n"
    << "messenger: {linear_mass: 1.08, tension: " << kTm << "}\n"
    << "droppers: {positions: [2.0, 18.0], axial_stiffness: 200000, linear_mass: 0.0}\n"
    << "stitch_wire: {length: 8.0, tension: " << kTs << ", linear_mass: 0.31}\n"
    << "contact: {rub_length: 0.0}\n"
    << "numerics: {element_length: " << element << "}\n";
  return y.str();
}

// The same line as a network of strings: each wire a chain of nodes at its stations (fixed ones
// at the rigid supports), T / l between neighbours; droppers and clamps as springs. Solved for a
// force F up at the contact wire's node at `probe` (a station of the chain).
double network_uplift(const cs::Model& m, double probe, double F) {
  std::map<std::string, int> id;
  auto node = [&](const std::string& name) {
    const auto it = id.find(name);
    if (it != id.end()) return it->second;
    const int k = static_cast<int>(id.size());
    id[name] = k;
    return k;
  };
  struct Link { int a, b; double k; };  // b = -1: to a fixed point
  std::vector<Link> links;
  auto chain = [&](const std::string& wire, std::vector<double> xs, const std::vector<double>& fixed, double T) {
    xs.insert(xs.end(), fixed.begin(), fixed.end());
    std::sort(xs.begin(), xs.end());
    auto is_fixed = [&](double x) { return std::find(fixed.begin(), fixed.end(), x) != fixed.end(); };
    auto at = [&](double x) { return is_fixed(x) ? -1 : node(wire + std::to_string(x)); };
    for (std::size_t i = 0; i + 1 < xs.size(); ++i) {
      int a = at(xs[i]), b = at(xs[i + 1]);
      if (a < 0) std::swap(a, b);
      links.push_back({a, b, T / (xs[i + 1] - xs[i])});
    }
  };
  std::vector<double> cx{2.0, 18.0, 22.0, 38.0};
  if (std::find(cx.begin(), cx.end(), probe) == cx.end()) cx.push_back(probe);
  chain("c", cx, {0.0, 20.0, 40.0}, kTc);
  chain("m", {2.0, 16.0, 24.0, 38.0}, {0.0, 20.0, 40.0}, kTm);
  chain("s", {16.0, 18.0, 22.0, 24.0}, {}, kTs);
  for (const cs::Dropper& d : m.droppers) {
    const bool on_stitch = d.x > 16.0 && d.x < 24.0;
    links.push_back({node("c" + std::to_string(d.x)), node((on_stitch ? "s" : "m") + std::to_string(d.x)), d.stiffness});
  }
  for (double x : {16.0, 24.0}) links.push_back({node("m" + std::to_string(x)), node("s" + std::to_string(x)), cs::kStitchClampStiffness});
  const int n = static_cast<int>(id.size());
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n, n);
  for (const Link& l : links) {
    K(l.a, l.a) += l.k;
    if (l.b >= 0) {
      K(l.b, l.b) += l.k;
      K(l.a, l.b) -= l.k;
      K(l.b, l.a) -= l.k;
    }
  }
  Eigen::VectorXd f = Eigen::VectorXd::Zero(n);
  f[node("c" + std::to_string(probe))] = F;
  return K.ldlt().solve(f)[node("c" + std::to_string(probe))];
}

}  // namespace

// (a) The statics against the string network. With no bending stiffness the beam elements
// (Hermite cubics, C1 at the nodes) cannot take a string's kink at a load point exactly: they
// round it over the elements beside it, an error first order in the element length h (the
// share of each segment that is rounded). So the error must fall about fourfold from h = 0.2 m
// to h = 0.05 m, and the first-order extrapolation (4 u(h/4) - u(h)) / 3 must meet the network
// to 0.05 %, where the O(h^2) remainder is far smaller; at h = 0.05 m itself 0.5 %.
TEST(StitchedCatenary, StaticsMatchAStringNetwork) {
  const double F = 10.0;  // N: every dropper stays taut (each holds about 100 N of contact wire)
  const cs::ElasticityProbe coarse(cs::load_scene_string(network_yaml(0.2)), F);
  const cs::ElasticityProbe fine(cs::load_scene_string(network_yaml(0.05)), F);
  ASSERT_EQ(fine.model().clamps.size(), 2u);
  for (double x : {10.0, 18.0, 22.0, 30.0}) {  // under the messenger's droppers and the stitch wire's
    const double expected = network_uplift(fine.model(), x, F);
    const double uc = coarse.uplift(x).at(0), uf = fine.uplift(x).at(0);
    const double ec = std::fabs(uc - expected) / expected, ef = std::fabs(uf - expected) / expected;
    EXPECT_LT(ef, 5e-3) << "probe at " << x << " m: " << uf << " against " << expected;
    EXPECT_GT(ec / ef, 3.0) << "probe at " << x << " m: the error is not first order in h";
    EXPECT_LT(ec / ef, 5.0) << "probe at " << x << " m: the error is not first order in h";
    EXPECT_NEAR((4.0 * uf - uc) / 3.0, expected, 5e-4 * expected) << "probe at " << x << " m";
  }
}

namespace {

cs::Scene reference_with_stitch(double length) {
  cs::Scene s = cs::load_scene_file(test_scenes::kReference);
  cs::StitchWireSpec st;
  st.length = length;
  st.tension = kTs;
  st.linear_mass = 0.31;
  st.bending_stiffness = 10.7;
  st.clamp_mass = 0.38;
  s.stitch_wire = st;
  for (cs::SectionSpec& sec : s.sections) sec.stitch_wire = st;
  return s;
}

// Elasticity (m/N) of the contact wire along one span, every 0.5 m from its first support.
std::vector<double> span_elasticity(const cs::Scene& scene, double first_support, double span) {
  const double F = 100.0;
  const cs::ElasticityProbe probe(scene, F);
  std::vector<double> e;
  for (double x = first_support; x <= first_support + span + 1e-9; x += 0.5) e.push_back(probe.uplift(x).at(0) / F);
  return e;
}

double uniformity(const std::vector<double>& e) {  // (max - min) / (max + min), as EN 50119 states it
  const auto [lo, hi] = std::minmax_element(e.begin(), e.end());
  return (*hi - *lo) / (*hi + *lo);
}

}  // namespace

// (b) The limit: a stitch wire that carries no dropper only adds its tension to the messenger's
// over its length beside the support, so its effect on the elasticity shrinks with its length:
// T_s / T_m x L / span is 0.2 % at L = 0.5 m on the reference line (0.22 x 0.5 / 55, an upper
// bound: only the messenger's share of the elasticity feels it), the tolerance; it must also be
// below the effect at L = 4 m (both carry no dropper: the first is at 4.5 m).
TEST(StitchedCatenary, AShortStitchWireGivesTheSimpleLinesElasticity) {
  const double x0 = 220.0, span = 55.0;
  const std::vector<double> simple = span_elasticity(cs::load_scene_file(test_scenes::kReference), x0, span);
  auto largest_change = [&](double length) {
    const std::vector<double> e = span_elasticity(reference_with_stitch(length), x0, span);
    double worst = 0.0;
    for (std::size_t i = 0; i < e.size(); ++i) worst = std::max(worst, std::fabs(e[i] - simple[i]) / simple[i]);
    return worst;
  };
  const double short_wire = largest_change(0.5), longer = largest_change(4.0);
  EXPECT_LT(short_wire, 2e-3) << "L = 4 m: " << longer;
  EXPECT_LT(short_wire, longer);
}

// (c) What the stitch wire is for, on the reference line and its stitched twin: the contact
// wire at the support hangs from a soft string instead of the messenger's support, so it is
// more elastic there and the elasticity is more uniform over the span; mid-span, 19.5 m from
// the nearest clamp, the tensions alone set it (within 5 %, the messenger's share of the
// stitch wire's weight).
TEST(StitchedCatenary, ElasticityIsMoreUniformOverTheSpan) {
  const double x0 = 220.0, span = 55.0;
  const std::vector<double> simple = span_elasticity(cs::load_scene_file(test_scenes::kReference), x0, span);
  const std::vector<double> stitched = span_elasticity(cs::load_scene_file(test_scenes::kReferenceStitched), x0, span);
  ASSERT_EQ(simple.size(), stitched.size());
  EXPECT_GT(stitched.front(), simple.front());  // at the support
  const std::size_t mid = simple.size() / 2;
  EXPECT_NEAR(stitched[mid], simple[mid], 0.05 * simple[mid]);
  EXPECT_LT(uniformity(stitched), uniformity(simple));
}

// (d) The design state is an equilibrium: on every free wire node, the stitch wires' included, the
// constant load is balanced by the droppers' and clamps' design forces alone (round-off only).
TEST(StitchedCatenary, TheDesignStateIsAnEquilibrium) {
  const cs::Model m = cs::build_model(cs::load_scene_file(test_scenes::kReferenceStitched));
  ASSERT_FALSE(m.clamps.empty());
  test_scenes::expect_design_equilibrium(m);
  // Each stitch wire hangs by its clamps: their forces carry its weight and its droppers'.
  for (const cs::Section& sec : m.sections)
    for (int wi : sec.stitch_wires) {
      const cs::Wire& w = m.wires[wi];
      double clamps = 0.0, carried = 0.0;
      for (const cs::WireClamp& c : m.clamps)
        if (c.stitch_dof >= w.w_dof && c.stitch_dof < w.w_dof + w.nodes()) clamps += c.static_force;
      for (int i = 0; i < w.nodes(); ++i) carried += 9.81 * m.mass[w.w_dof + i];
      for (const cs::Dropper& d : m.droppers)
        if (d.messenger_dof >= w.w_dof && d.messenger_dof < w.w_dof + w.nodes()) carried += d.static_tension;
      EXPECT_NEAR(clamps, carried, 1e-9 * carried) << w.name;
    }
}

// (e) The contact force at speed: a stitched line's more uniform elasticity excites the
// pantograph less at the span passing frequency, so the spread of the contact force (its
// standard deviation, 20 Hz as the standards filter it) is lower than on the simple line at the
// same speed, the mean the same (within 1 %: the mean is the uplift either way).
TEST(StitchedCatenary, ContactForceSpreadsLessAtSpeed) {
  auto pass = [](const std::string& path) {
    cs::Simulation sim(cs::load_scene_file(path));
    const cs::Model& m = sim.model();
    double x0 = 0.0, x1 = 0.0;
    cs::analysis_section(m, &x0, &x1);
    std::vector<double> force;
    std::vector<bool> inside;
    while (!sim.finished()) {
      EXPECT_EQ(sim.step(), cs::StepStatus::kOk) << sim.status_message();
      force.push_back(sim.state().pantograph_force_on(m, 0, 0));
      inside.push_back(sim.state().front >= x0 && sim.state().front <= x1);
    }
    const std::vector<double> filtered = cs::lowpass_zero_phase(force, 1.0 / m.dt, 20.0);
    double sum = 0.0, sq = 0.0;
    long n = 0;
    for (std::size_t i = 0; i < filtered.size(); ++i)
      if (inside[i]) sum += filtered[i], sq += filtered[i] * filtered[i], ++n;
    const double mean = sum / n;
    return std::make_pair(mean, std::sqrt(sq / n - mean * mean));
  };
  const auto simple = pass(test_scenes::kReference), stitched = pass(test_scenes::kReferenceStitched);
  EXPECT_NEAR(stitched.first, simple.first, 0.01 * simple.first);
  EXPECT_LT(stitched.second, simple.second);
}

TEST(StitchedCatenary, BadInputIsRefusedByName) {
  const auto refused = test_scenes::expect_refused;
  const std::string y = network_yaml(0.25);
  auto with = [&](const std::string& from, const std::string& to) {
    std::string s = y;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  refused(with("length: 8.0", "length: 0"), "stitch_wire.length");
  refused(with("length: 8.0", "length: 20.0"), "stitch_wire.length");  // not shorter than the span
  refused(with("tension: 3500", "tension: -1"), "stitch_wire.tension");
  refused(with("linear_mass: 0.31", "linear_mass: 0.31, colour: red"), "stitch_wire.colour");
  refused(with("span_count: 2", "span_count: 1"), "stitch_wire");
  refused(with("stitch_wire: {length: 8.0, tension: 3500, linear_mass: 0.31}", "stitch_wire: off"), "stitch_wire");
  refused(with("droppers: {positions: [2.0, 18.0], axial_stiffness: 200000, linear_mass: 0.0}\n", ""), "stitch_wire");
  refused(y + "stagger:\n  contact_wire: [0.2, -0.2]\n", "stagger");
  refused("name: r\nline: {span_length: 10.0, span_count: 3}\n"
          "conductor_rail: {linear_mass: 7.27, bending_stiffness: 2.8e5, support_stiffness: 5e6}\n"
          "stitch_wire: {length: 8.0, tension: 3500, linear_mass: 0.31}\n",
          "stitch_wire");
}

// A section may leave out the stitch wire its line's defaults give (a simple section on a
// stitched line), with `stitch_wire: none`.
TEST(StitchedCatenary, ASectionCanLeaveTheStitchWireOut) {
  std::ifstream in(test_scenes::scene_path("reference_55m_two_sections.yaml"));
  std::string two((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto replace = [&](const std::string& from, const std::string& to) {
    ASSERT_NE(two.find(from), std::string::npos) << from;
    two.replace(two.find(from), from.size(), to);
  };
  replace("sections:\n", "stitch_wire: {length: 16.0, tension: 3500, linear_mass: 0.31}\nsections:\n");
  replace("    span_count: 10\noverlap:", "    span_count: 10\n    stitch_wire: none\noverlap:");
  const cs::Scene scene = cs::load_scene_string(two);
  ASSERT_TRUE(scene.sections[0].stitch_wire.has_value());
  EXPECT_FALSE(scene.sections[1].stitch_wire.has_value());
  const cs::Model m = cs::build_model(scene);
  EXPECT_EQ(m.sections[0].stitch_wires.size(), 9u);  // at the section's 9 intermediate supports
  EXPECT_TRUE(m.sections[1].stitch_wires.empty());
}

// A stitch wire too slack for its droppers hangs below the contact wire: refused, naming it.
TEST(StitchedCatenary, AStitchWireBelowTheContactWireIsRefused) {
  std::string y = network_yaml(0.25);
  y.replace(y.find("tension: 3500"), 13, "tension: 100");
  try {
    cs::build_model(cs::load_scene_string(y));
    ADD_FAILURE() << "a stitch wire of 100 N was accepted";
  } catch (const cs::SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("stitch wire"), std::string::npos) << e.what();
  }
}

// The memory check before building counts what a stitched line adds: every node the model has
// (the clamps' stations on each wire of the section, the stitch wires' own) is within the
// estimate, on the reference stitched line and with longer stitch wires (24 m: two droppers a side).
TEST(StitchedCatenary, TheMemoryEstimateHoldsTheStitchWires) {
  for (double length : {16.0, 24.0}) {
    cs::Scene scene = cs::load_scene_file(test_scenes::kReferenceStitched);
    for (cs::SectionSpec& sec : scene.sections) sec.stitch_wire->length = length;
    const cs::Model m = cs::build_model(scene);
    double nodes = 0.0;
    for (const cs::Wire& w : m.wires) nodes += w.nodes();
    EXPECT_GE(cs::estimate_model_bytes(m.scene) / cs::kModelBytesPerNode, nodes) << "stitch wires of " << length << " m";
  }
}

// The endless block carries the stitch wires: at each move every stitch wire takes the state of
// the one a span on. The same 20 spans of pass, from station 1650 m, on the endless stitched line
// and on a finite 60-span one whose anchors the window never reaches, must agree at every step to
// rounding, as the simple line's (test_endless_line: 1e-4 N); a stitch wire's state handed to the
// wrong one, or lost, would change the force by newtons at the next support.
TEST(StitchedCatenary, TheEndlessBlockMovesTheStitchWiresExactly) {
  const std::vector<std::string> pass = {"train.start=1650", "train.end=2750", "numerics.preset=balanced",
                                         "numerics.window=auto"};
  std::vector<std::string> finite = pass;
  finite.push_back("line.span_count=60");
  cs::Simulation a(test_scenes::endless_scene(test_scenes::kReferenceStitched, pass));
  cs::Simulation b(cs::load_scene_file(test_scenes::kReferenceStitched, finite));
  ASSERT_TRUE(a.model().endless);
  ASSERT_FALSE(a.model().sections[0].stitch_wires.empty());
  double worst = 0.0, offset_seen = 0.0;
  while (true) {
    const cs::StepStatus sa = a.step(), sb = b.step();
    ASSERT_EQ(sa, sb) << a.status_message() << " / " << b.status_message();
    if (sa != cs::StepStatus::kOk) break;
    worst = std::max(worst, std::fabs(cs::total_contact_force(a.model(), a.state(), 0) -
                                      cs::total_contact_force(b.model(), b.state(), 0)));
    offset_seen = a.state().line_offset;
  }
  EXPECT_GT(offset_seen - a.model().initial_line_offset, 15 * 55.0);  // the block was moved along
  EXPECT_LT(worst, 1e-4);
}
