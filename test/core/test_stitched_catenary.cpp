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

#include "catenary_sim/core/engine/initial_state.hpp"
#include "catenary_sim/core/engine/lateral_energy.hpp"
#include "catenary_sim/core/model/build_model.hpp"
#include "catenary_sim/core/model/lateral.hpp"
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
#include "engine/forces.hpp"

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
// force F up at the contact wire's node at `probe` (a station of the chain). `spans` spans of 20 m
// with droppers at 2 m and 18 m of each; a stitch wire of length L at each support x of
// `stitches` ({x, L}), its clamps at x -/+ L / 2, the droppers strictly between them on it.
double network_uplift(const cs::Model& m, double probe, double F, int spans = 2,
                      const std::vector<std::pair<double, double>>& stitches = {{20.0, 8.0}}) {
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
  std::vector<double> supports, droppers;
  for (int k = 0; k <= spans; ++k) supports.push_back(20.0 * k);
  for (int k = 0; k < spans; ++k) droppers.insert(droppers.end(), {20.0 * k + 2.0, 20.0 * k + 18.0});
  std::vector<double> cx = droppers;
  if (std::find(cx.begin(), cx.end(), probe) == cx.end()) cx.push_back(probe);
  chain("c", cx, supports, kTc);
  // The stitch wire a dropper at xd hangs from (-1: the messenger).
  auto stitch_of = [&](double xd) {
    for (std::size_t j = 0; j < stitches.size(); ++j)
      if (std::fabs(xd - stitches[j].first) < 0.5 * stitches[j].second) return static_cast<int>(j);
    return -1;
  };
  std::vector<double> mx;
  for (double xd : droppers)
    if (stitch_of(xd) < 0) mx.push_back(xd);
  for (std::size_t j = 0; j < stitches.size(); ++j) {
    const double a = stitches[j].first - 0.5 * stitches[j].second, b = stitches[j].first + 0.5 * stitches[j].second;
    mx.insert(mx.end(), {a, b});
    std::vector<double> sx{a, b};
    for (double xd : droppers)
      if (stitch_of(xd) == static_cast<int>(j)) sx.push_back(xd);
    chain("s" + std::to_string(j) + "_", sx, {}, kTs);
    for (double x : {a, b}) links.push_back({node("m" + std::to_string(x)), node("s" + std::to_string(j) + "_" + std::to_string(x)), cs::kWireClampStiffness});
  }
  chain("m", mx, supports, kTm);
  for (const cs::Dropper& d : m.droppers) {
    const int j = stitch_of(d.x);
    links.push_back({node("c" + std::to_string(d.x)), node((j >= 0 ? "s" + std::to_string(j) + "_" : std::string("m")) + std::to_string(d.x)), d.stiffness});
  }
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

// (a') A stitch wire of its own length at each support (`lengths`): three spans of 20 m, 8 m of
// stitch wire at the first intermediate support (clamps at 16 and 24 m) and 6 m at the second
// (37 and 43 m), against the string network with the same wires; the same tolerances as (a).
// Each stitch wire carries the droppers between its own clamps.
TEST(StitchedCatenary, EachSupportsOwnStitchWireLengthMatchesTheStringNetwork) {
  const double F = 100.0;
  auto yaml = [](double element) {
    std::string y = network_yaml(element);
    y.replace(y.find("span_count: 2"), 13, "span_count: 3");
    y.replace(y.find("length: 8.0"), 11, "lengths: [8.0, 6.0]");
    return y;
  };
  const cs::ElasticityProbe coarse(cs::load_scene_string(yaml(0.2)), F);
  const cs::ElasticityProbe fine(cs::load_scene_string(yaml(0.05)), F);
  ASSERT_EQ(fine.model().clamps.size(), 4u);
  const std::vector<std::pair<double, double>> stitches{{20.0, 8.0}, {40.0, 6.0}};
  for (double x : {10.0, 18.0, 22.0, 30.0, 38.0, 42.0, 50.0}) {
    const double expected = network_uplift(fine.model(), x, F, 3, stitches);
    const double uc = coarse.uplift(x).at(0), uf = fine.uplift(x).at(0);
    EXPECT_LT(std::fabs(uf - expected) / expected, 5e-3) << "probe at " << x << " m: " << uf << " against " << expected;
    EXPECT_NEAR((4.0 * uf - uc) / 3.0, expected, 5e-4 * expected) << "probe at " << x << " m";
  }
  // Written as one length for every support, lengths gives the model that length gives.
  std::string same = network_yaml(0.2);
  same.replace(same.find("length: 8.0"), 11, "lengths: [8.0]");
  const cs::ElasticityProbe one(cs::load_scene_string(same), F);
  const cs::ElasticityProbe uniform(cs::load_scene_string(network_yaml(0.2)), F);
  for (double x : {18.0, 30.0}) EXPECT_EQ(one.uplift(x).at(0), uniform.uplift(x).at(0)) << "probe at " << x << " m";
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
    for (int wi : sec.clamped_wires) {
      const cs::Wire& w = m.wires[wi];
      double clamps = 0.0, carried = 0.0;
      for (const cs::WireClamp& c : m.clamps)
        if (c.lower_dof >= w.w_dof && c.lower_dof < w.w_dof + w.nodes()) clamps += c.static_force;
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
  // Each clamp within its span, length / 2 from its support: the two spans of a 2-span section are
  // its end spans, one clamp each (length < 2 x 20 m); the inner span of 3 holds two (< 20 m).
  auto stitch_length = [](std::string yaml, const std::string& length) {
    return yaml.replace(yaml.find("length: 8.0"), 11, "length: " + length);
  };
  refused(stitch_length(y, "40.0"), "stitch_wire.length");
  EXPECT_NO_THROW(cs::Simulation(cs::load_scene_string(stitch_length(y, "36.0"))));
  const std::string inner = test_scenes::refusal_of_yaml(stitch_length(with("span_count: 2", "span_count: 3"), "20.0"));
  for (const char* word : {"stitch_wire.length", "(0, 20) m", "span 1, 20 m"}) EXPECT_NE(inner.find(word), std::string::npos) << inner;
  // at_supports: the intermediate supports that carry one, whole numbers from 1 to the spans less
  // one, increasing; a support left out frees its spans' room (3 spans, the inner one holding the
  // clamp of support 1 alone: length up to twice it).
  const std::string three_spans = with("span_count: 2", "span_count: 3");
  auto at = [&](const std::string& base, const std::string& list) {
    std::string yaml = base;
    return yaml.replace(yaml.find("linear_mass: 0.31}"), 18, "linear_mass: 0.31, at_supports: " + list + "}");
  };
  refused(at(y, "[0]"), "stitch_wire.at_supports");
  refused(at(y, "[2]"), "stitch_wire.at_supports");           // 2 spans: support 1 only
  refused(at(three_spans, "[2, 1]"), "stitch_wire.at_supports[1]");
  refused(at(three_spans, "[1, 1]"), "stitch_wire.at_supports[1]");
  refused(at(y, "[1.5]"), "stitch_wire.at_supports[0]");
  refused(at(y, "[]"), "stitch_wire.at_supports");
  refused(at(y, "one"), "stitch_wire.at_supports");
  refused(stitch_length(at(three_spans, "[1]"), "40.0"), "stitch_wire.length");
  EXPECT_NO_THROW(cs::Simulation(cs::load_scene_string(stitch_length(at(three_spans, "[1]"), "36.0"))));
  // The endless line's one span repeats: every support carries one.
  const std::string endless = test_scenes::refusal_of_yaml(test_scenes::endless_yaml(test_scenes::kReferenceStitched),
                                                            {"numerics.window=auto", "stitch_wire.at_supports=[1]"});
  EXPECT_NE(endless.find("stitch_wire.at_supports"), std::string::npos) << "endless line: " << endless;
  // lengths: one per carrying support, each support's clamps within its spans; not with length.
  auto lengths = [](std::string yaml, const std::string& list) {
    return yaml.replace(yaml.find("length: 8.0"), 11, "lengths: " + list);
  };
  refused(lengths(y, "[8.0, 8.0]"), "stitch_wire.lengths");  // 2 spans: one support
  refused(lengths(y, "[]"), "stitch_wire.lengths");
  refused(lengths(y, "[0.0]"), "stitch_wire.lengths[0]");
  refused(lengths(y, "[8.0]") + "stitch_wire: {length: 8.0}\n", "stitch_wire");
  refused(with("length: 8.0", "length: 8.0, lengths: [8.0]"), "stitch_wire.length");
  // 3 spans of 20 m: the inner span holds the halves of both supports' stitch wires (10 + 11 m).
  const std::string too_long = test_scenes::refusal_of_yaml(lengths(three_spans, "[20.0, 22.0]"));
  for (const char* word : {"stitch_wire.lengths[", "span 1", "10 + 11 m"}) EXPECT_NE(too_long.find(word), std::string::npos) << too_long;
  EXPECT_EQ(test_scenes::refusal_of_yaml(lengths(three_spans, "[20.0, 18.0]")), "");
  EXPECT_EQ(test_scenes::refusal_of_yaml(lengths(at(three_spans, "[2]"), "[38.0]")), "");  // one clamp a span: < 2 x 20 m
  refused(lengths(at(three_spans, "[2]"), "[20.0, 20.0]"), "stitch_wire.lengths");
  const std::string endless_lengths = test_scenes::refusal_of_yaml(
      test_scenes::endless_yaml(test_scenes::kReferenceStitched), {"numerics.window=auto", "stitch_wire.length=null", "stitch_wire.lengths=[18.0]"});
  EXPECT_NE(endless_lengths.find("stitch_wire.lengths"), std::string::npos) << "endless line: " << endless_lengths;
  refused(with("tension: 3500", "tension: -1"), "stitch_wire.tension");
  refused(with("linear_mass: 0.31", "linear_mass: 0.31, colour: red"), "stitch_wire.colour");
  refused(with("span_count: 2", "span_count: 1"), "stitch_wire");
  refused(with("stitch_wire: {length: 8.0, tension: 3500, linear_mass: 0.31}", "stitch_wire: off"), "stitch_wire");
  refused(with("droppers: {positions: [2.0, 18.0], axial_stiffness: 200000, linear_mass: 0.0}\n", ""), "stitch_wire");
  refused(y + "wind: {speed: 20, stitch_wire: {diameter: 0}}\n", "wind.stitch_wire.diameter");
  refused(y + "wind: {speed: 20, stitch_wire: {diameter: 0.0075, drag_coefficient: 4}}\n",
          "wind.stitch_wire.drag_coefficient");
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
  EXPECT_EQ(m.sections[0].clamped_wires.size(), 9u);  // at the section's 9 intermediate supports
  EXPECT_TRUE(m.sections[1].clamped_wires.empty());
}

// A stitch wire too slack for its droppers hangs below the contact wire: refused by its tension
// (the field, as scene fields are named: Python's SceneError.field reads it), with its length as
// the other remedy.
TEST(StitchedCatenary, AStitchWireBelowTheContactWireIsRefused) {
  std::string y = network_yaml(0.25);
  y.replace(y.find("tension: 3500"), 13, "tension: 100");
  try {
    cs::build_model(cs::load_scene_string(y));
    ADD_FAILURE() << "a stitch wire of 100 N was accepted";
  } catch (const cs::SceneError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("scene field 'stitch_wire.tension' = 100 N: ", 0), 0u) << what;
    EXPECT_NE(what.find("stitch wire hangs"), std::string::npos) << what;
    EXPECT_NE(what.find("shorten stitch_wire.length"), std::string::npos) << what;
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
  ASSERT_FALSE(a.model().sections[0].clamped_wires.empty());
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

// ---- The stitched line as a 3-D line (the stitch wire in plan: model/lateral.hpp) ----

namespace {

// The network line of network_yaml with a steady cross wind of 30 m/s on the stitch wire alone
// (the contact wire's and messenger's Cd 0), no stagger: the stitch wire's share of the lateral
// plane is then what its own wind load makes of it.
std::string windy_network_yaml(double element) {
  return network_yaml(element) +
         "wind: {speed: 30, direction: 90, air_density: 1.225, contact_wire: {drag_coefficient: 0},\n"
         "       messenger: {drag_coefficient: 0}, stitch_wire: {diameter: 0.0075, drag_coefficient: 1.0}}\n";
}

// The stitch wire's lateral deflection at its middle (the support) relative to the chord between
// its two ends, from the model's lateral statics under the mean wind, and the same from the
// string's closed form: a string of tension T_s between its ends under the uniform load
// q = 0.5 rho Cd d V^2, pulled at each of its droppers by the pendulum S / l toward the contact
// wire (Green's function G(x, xi) = x_< (L - x_>) / (T_s L)), the ends' and the contact wire's
// positions taken from the statics (they are the string's boundary values, not what is checked).
std::pair<double, double> stitch_sag_and_string(const cs::Model& m) {
  const cs::LateralModel& lat = *m.lateral;
  const int wi = m.sections[0].clamped_wires.at(0);
  const cs::Wire& w = lat.wires[wi];
  const Eigen::VectorXd& y = lat.initial;
  const double x0 = w.x.front(), L = w.x.back() - x0;
  const double y0 = y[w.w_dof], y1 = y[w.w_dof + w.nodes() - 1];
  auto chord = [&](double x) { return y0 + (y1 - y0) * (x - x0) / L; };
  const double q = 0.5 * 1.225 * 1.0 * 0.0075 * 30.0 * 30.0;  // N/m
  auto G = [&](double a, double b) { return std::min(a, b) * (L - std::max(a, b)) / (kTs * L); };
  struct Pull { double x, k, yc; };
  std::vector<Pull> pulls;
  for (const cs::LateralPendulum& p : lat.pendulums)
    if (p.messenger >= w.w_dof && p.messenger < w.w_dof + w.nodes()) {
      const cs::Dropper& d = m.droppers[p.dropper];
      pulls.push_back({d.x - x0, std::max(0.0, d.static_tension) * p.inv_length, y[p.contact]});
    }
  EXPECT_EQ(pulls.size(), 2u);  // the droppers at 18 m and 22 m
  // r_i + sum_j k_j G(x_i, x_j) r_j = q x_i (L - x_i) / (2 T_s) - sum_j k_j G(x_i, x_j) (chord_j - y_c,j)
  const int n = static_cast<int>(pulls.size());
  Eigen::MatrixXd A = Eigen::MatrixXd::Identity(n, n);
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) {
    b[i] = q * pulls[i].x * (L - pulls[i].x) / (2.0 * kTs);
    for (int j = 0; j < n; ++j) {
      A(i, j) += pulls[j].k * G(pulls[i].x, pulls[j].x);
      b[i] -= pulls[j].k * G(pulls[i].x, pulls[j].x) * (chord(x0 + pulls[j].x) - pulls[j].yc);
    }
  }
  const Eigen::VectorXd r = A.lu().solve(b);
  const double xm = 0.5 * L;
  double string = q * L * L / (8.0 * kTs);
  for (int j = 0; j < n; ++j) string -= pulls[j].k * G(xm, pulls[j].x) * (chord(x0 + pulls[j].x) + r[j] - pulls[j].yc);
  int mid = 0;
  for (int i = 0; i < w.nodes(); ++i)
    if (std::fabs(w.x[i] - (x0 + xm)) < std::fabs(w.x[mid] - (x0 + xm))) mid = i;
  EXPECT_NEAR(w.x[mid], x0 + xm, 1e-9);
  return {y[w.w_dof + mid] - chord(x0 + xm), string};
}

}  // namespace

// (f) The stitch wire in plan under a steady cross wind: between its two clamps on the messenger
// a tensioned string under the wind's uniform load, q L^2 / (8 T_s) = 9.45 mm at its middle for
// 8 m at 3.5 kN in 30 m/s, less what its two droppers' pendulums (S / l, some 100 N/m) hold back
// (0.6 mm). The statics is exact for the string but at the pendulums' kinks, which the elements
// round over the elements beside them (Hermite cubics are C1; the bending stiffness is 0 here, as
// in (a)): an error that is a fraction of the pendulums' share and falls with the element length.
// So within 0.5 % of the sag at h = 0.25 m (a twelfth of that share), 0.05 % at h = 0.05 m, and
// smaller at the finer mesh. A stitch wire without its clamps in plan hangs from its pendulums
// alone (centimetres off); one with the messenger's drag diameter (10.5 mm) sags 40 % more.
TEST(StitchedCatenary, StitchWireInPlanIsAStringBetweenItsClamps) {
  double error_coarse = 0.0;
  for (double h : {0.25, 0.05}) {
    const cs::Model m = cs::build_model(cs::load_scene_string(windy_network_yaml(h)));
    ASSERT_TRUE(m.lateral);
    ASSERT_EQ(m.lateral->clamps.size(), 2u);
    const auto [sag, string] = stitch_sag_and_string(m);
    const double q = 0.5 * 1.225 * 0.0075 * 900.0;
    std::printf("h %.2f m: stitch wire %.4f mm relative to its chord, string %.4f mm (q L^2 / 8 T_s %.4f mm)\n", h,
                1e3 * sag, 1e3 * string, 1e3 * q * 64.0 / (8.0 * kTs));
    const double error = std::fabs(sag - string);
    EXPECT_GT(string, 0.9 * q * 64.0 / (8.0 * kTs));  // the pendulums a correction, not the answer
    EXPECT_LT(error, (h > 0.1 ? 5e-3 : 5e-4) * string) << "h " << h;
    if (h > 0.1) error_coarse = error;
    else EXPECT_LT(error, error_coarse);
  }
  // The step holds the statics' stiffness (the clamps, pendulums and wires): started in that
  // static state, with no pantograph, the lateral plane stays there to round-off (forces of 1e-12
  // of the wind's); a step without the clamps in plan would let the stitch wire go by millimetres
  // (their 17 N of wind reaction). 1 um is a ten-thousandth of the sag.
  cs::Simulation sim(cs::load_scene_string(windy_network_yaml(0.25)));
  ASSERT_TRUE(sim.model().pantographs.empty());
  for (int i = 0; i < 4000; ++i) ASSERT_EQ(sim.step(), cs::StepStatus::kOk) << sim.status_message();
  EXPECT_LT((sim.state().lateral.y - sim.model().lateral->initial).cwiseAbs().maxCoeff(), 1e-6);
}

namespace {

// The lateral position of the stitch wire under the leading collector, at its station (NaN where
// none is): the stitch wires' part in the window and the endless block.
double stitch_wire_under_pantograph(const cs::Simulation& sim) {
  const cs::Model& m = sim.model();
  const double xp = sim.state().front - m.pantographs[0].position;
  for (int wi : m.sections[0].clamped_wires) {
    const cs::Wire& w = m.lateral->wires[wi];
    if (xp < w.x.front() || xp > w.x.back()) continue;
    const int i = static_cast<int>(std::lower_bound(w.x.begin(), w.x.end(), xp) - w.x.begin());
    return sim.state().lateral.y[w.w_dof + i];
  }
  return std::nan("");
}

// The largest differences over two passes side by side: the leading collector's contact point
// across the strip, the stitch wire under it; the contact force at the end.
struct LateralDifference {
  double contact_point = 0.0, stitch_wire = 0.0, final_contact_force = 0.0;
  int compared = 0, on_stitch = 0;
};

LateralDifference compare_passes(cs::Simulation& a, cs::Simulation& b) {
  LateralDifference d;
  while (true) {
    const cs::StepStatus sa = a.step(), sb = b.step();
    EXPECT_EQ(sa, sb) << a.status_message() << " / " << b.status_message();
    if (sa != cs::StepStatus::kOk || sb != cs::StepStatus::kOk) break;
    const double ya = a.state().lateral.collector_lateral[0], yb = b.state().lateral.collector_lateral[0];
    if (std::isfinite(ya) && std::isfinite(yb)) {
      d.contact_point = std::max(d.contact_point, std::fabs(ya - yb));
      ++d.compared;
    }
    const double sa_y = stitch_wire_under_pantograph(a), sb_y = stitch_wire_under_pantograph(b);
    EXPECT_EQ(std::isfinite(sa_y), std::isfinite(sb_y));
    if (std::isfinite(sa_y) && std::isfinite(sb_y)) {
      d.stitch_wire = std::max(d.stitch_wire, std::fabs(sa_y - sb_y));
      ++d.on_stitch;
    }
    d.final_contact_force = std::fabs(cs::total_contact_force(a.model(), a.state(), 0) -
                                      cs::total_contact_force(b.model(), b.state(), 0));
  }
  return d;
}

}  // namespace

// (g) The limit: a stitched 3-D line with no stagger, no wind and no curve (the contact wire's
// stagger given as 0, so the lateral plane is built) has nothing that moves a wire sideways: the
// lateral statics is 0, every lateral force stays exactly 0, so does every dropper's lean, and the
// vertical plane is the 2-D stitched line's bit for bit (as Lateral.VerticalResultsAreBitIdenticalWhenNoDropperLeans
// for the simple line): the contact force the same at every step, exactly.
TEST(StitchedCatenary, ThreeDimensionalLineWithoutStaggerOrWindIsTheTwoDimensionalOne) {
  // One scheme in both: the fast preset takes a 2-D line's supports and droppers at the step's
  // middle, a 3-D line's at q_n.
  const std::vector<std::string> base{"line.span_count=5", "numerics.preset=fast", "output.analysis_spans=[1,4]",
                                      "numerics.supports=explicit", "numerics.droppers=explicit"};
  std::vector<std::string> with = base;
  with.insert(with.end(), {"stagger.contact_wire=[0.0]", "stagger.steady_arm_stiffness=2.0e5"});
  cs::Simulation a(cs::load_scene_file(test_scenes::kReferenceStitched, base));
  cs::Simulation b(cs::load_scene_file(test_scenes::kReferenceStitched, with));
  ASSERT_FALSE(a.model().lateral);
  ASSERT_TRUE(b.model().lateral);
  ASSERT_FALSE(b.model().lateral->clamps.empty());
  ASSERT_EQ(a.model().dt, b.model().dt);
  std::int64_t steps = 0;
  bool same = true;
  while (a.step() == cs::StepStatus::kOk) {
    ASSERT_EQ(b.step(), cs::StepStatus::kOk) << b.status_message();
    same = same && a.state().contact_force == b.state().contact_force;
    ++steps;
  }
  EXPECT_TRUE(same);
  EXPECT_GT(steps, 1000);
  EXPECT_TRUE(a.state().u == b.state().u);
  EXPECT_EQ(b.state().lateral.y.cwiseAbs().maxCoeff(), 0.0);
}

// The window and the endless line with either damping step, on the stitched 3-D line.
class StitchedLateralDamping : public ::testing::TestWithParam<const char*> {
 protected:
  std::string damping() const { return std::string("numerics.damping=") + GetParam(); }
};

// (h) The moving window on the stitched 3-D line (stagger +-0.3 m, a steady 20 m/s cross wind, the
// pantograph swaying 3 cm at 0.8 Hz) against the whole line: a window edge on a support cuts the
// stitch wire there like any wire (the static force of its left-out half, a dashpot), its clamps
// and pendulums inside act as on the whole line. As Lateral's LateralDamping.WindowGivesTheFullLinesContactPoint
// the only differences are the echoes the window leaves out of the small lateral waves the
// pantograph sends through the droppers' changing tension: the contact point within 1 mm (1/600
// of the 0.6 m it sweeps), and the stitch wire under the pantograph as well (it moves with the
// contact wire through its two droppers' pendulums). A window that dropped the clamps would let
// the stitch wire go from its static state (the clamps hold 40 N of wind in it).
TEST_P(StitchedLateralDamping, WindowGivesTheWholeLinesLateralPlane) {
  const std::vector<std::string> pass = {"numerics.preset=balanced", "line.span_count=16", "wind.turbulence=null",
                                         "pantograph_head.sway.amplitude=0.03", "pantograph_head.sway.frequency=0.8",
                                         damping()};
  std::vector<std::string> windowed = pass;
  windowed.push_back("numerics.window=auto");
  cs::Simulation a(cs::load_scene_file(test_scenes::kReferenceStitched3d, pass));
  cs::Simulation b(cs::load_scene_file(test_scenes::kReferenceStitched3d, windowed));
  ASSERT_TRUE(b.model().lateral->windowed);
  const LateralDifference d = compare_passes(a, b);
  std::printf("window - whole line: contact point %.3g m, stitch wire %.3g m\n", d.contact_point, d.stitch_wire);
  EXPECT_GT(d.compared, 5000);
  EXPECT_GT(d.on_stitch, 1000);
  EXPECT_LT(d.contact_point, 1e-3);
  EXPECT_LT(d.stitch_wire, 1e-3);
}

// (i) The endless stitched 3-D line against a finite 60-span windowed one whose anchors the window
// never reaches, 20 spans of pass from station 1650 m, staggered +-0.3 m (the block moves by the
// stagger's two spans, and with it each stitch wire's lateral state to the one two supports
// behind), in a steady 20 m/s cross wind, swaying: the same window over the same spans, so the
// contact point within 1 mm and the contact force at the end within 0.6 N as for the simple line
// (Lateral's LateralDamping.EndlessLineGivesTheFiniteLinesContactPoint, whose reasons hold here),
// and the stitch wire under the pantograph within 1 mm. A stitch wire's lateral state handed to
// the wrong one, or left behind, puts it centimetres off at the next support.
TEST_P(StitchedLateralDamping, EndlessLineGivesTheFiniteLinesLateralPlane) {
  const std::vector<std::string> pass = {"train.start=1650",       "train.end=2750",          "numerics.preset=balanced",
                                         "numerics.window=auto",   "wind.turbulence=null",    "pantograph_head.sway.amplitude=0.03",
                                         "pantograph_head.sway.frequency=0.8", damping()};
  std::vector<std::string> finite = pass;
  finite.push_back("line.span_count=60");
  cs::Simulation a(test_scenes::endless_scene(test_scenes::kReferenceStitched3d, pass));
  cs::Simulation b(cs::load_scene_file(test_scenes::kReferenceStitched3d, finite));
  ASSERT_TRUE(a.model().endless);
  ASSERT_EQ(a.model().endless_shift_spans, 2);
  const LateralDifference d = compare_passes(a, b);
  std::printf("endless - finite line: contact point %.3g m, stitch wire %.3g m, contact force at the end %.3g N\n",
              d.contact_point, d.stitch_wire, d.final_contact_force);
  EXPECT_GT(a.state().line_offset - a.model().initial_line_offset, 15 * 55.0);
  EXPECT_GT(d.compared, 5000);
  EXPECT_GT(d.on_stitch, 1000);
  EXPECT_LT(d.contact_point, 1e-3);
  EXPECT_LT(d.stitch_wire, 1e-3);
  EXPECT_LT(d.final_contact_force, 0.6);
}

INSTANTIATE_TEST_SUITE_P(Damping, StitchedLateralDamping, ::testing::Values("half_step", "centred"));

// line_energy is the potential of the step's forces on a stitched line: at a state off the
// static one, its derivative along each DOF the stitch wires' clamps join (central differences,
// exact for the quadratic potentials of wires, supports, taut droppers and clamps up to rounding)
// is minus the force assemble_force gives there, undamped and at rest. A term of the clamps left
// out of the energy (their static force, hundreds of newtons, or k e) shows as that much force.
// Tolerance 1e-3 N: the rounding of energies of about 1e3 J differenced over 2e-6 m is ~1e-7 N.
TEST(StitchedCatenary, LineEnergyIsThePotentialOfTheStepsForces) {
  using namespace catenary_sim;
  Model m = build_model(
      load_scene_file(test_scenes::kReferenceStitched, {"line.span_count=3", "damping.alpha=0", "damping.beta=0", "pantographs=[]"}));
  ASSERT_FALSE(m.clamps.empty());
  State s = make_state(m);
  solve_initial_state(m, s);
  for (int i = 0; i < m.n_catenary_dof; ++i)
    if (m.inv_mass[i] > 0.0) s.u[i] += 1e-3 * std::sin(0.37 * i);
  s.v.setZero();
  Eigen::VectorXd z(m.n_dof), f(m.n_dof);
  assemble_force(m, s, s.u.data(), s.v.data(), z.data(), f.data());
  const double h = 1e-6;
  auto slope = [&](int i) {
    State p = s;
    p.u[i] += h;
    const double up = line_energy(m, p);
    p.u[i] -= 2.0 * h;
    return (up - line_energy(m, p)) / (2.0 * h);
  };
  for (const WireClamp& c : m.clamps)
    for (int i : {c.lower_dof, c.upper_dof}) EXPECT_NEAR(slope(i), -f[i], 1e-3) << "DOF " << i;
}
