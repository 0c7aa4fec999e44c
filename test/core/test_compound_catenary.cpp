// Compound catenary (docs/compound_catenary.md): droppers hang an auxiliary messenger from the
// messenger, hangers hang the contact wire from the auxiliary. Its design statics against strings
// solved by hand, the limit of a slack weightless auxiliary (the simple line), what the auxiliary
// is for (a more uniform elasticity, less force at the span period), the design state's balance,
// and bad input.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <sstream>
#include <string>
#include <vector>

#include "catenary_sim/core/model/build_model.hpp"
#include "catenary_sim/core/model/lateral.hpp"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/model/model_memory.hpp"
#include "catenary_sim/core/model/statics.hpp"
#include "catenary_sim/core/scene/scene.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "catenary_sim/core/output/zero_phase_filter.hpp"
#include "catenary_sim/core/simulation.hpp"
#include "../support/design_equilibrium.hpp"
#include "../support/scene_refusal.hpp"
#include "../support/scenes.hpp"

namespace cs = catenary_sim;

namespace {

constexpr double kG = 9.81, kMuC = 1.51, kMuA = 1.36, kTc = 14700.0, kTa = 14700.0, kH = 0.15;

// Two spans of 20 m on rigid supports, every wire a string (no bending stiffness), weightless
// droppers and hangers without clamps: droppers at 5 and 15 m, hangers every 5 m from 2.5 m.
std::string strings_yaml(double element) {
  std::ostringstream y;
  y << "name: strings\nline: {span_length: 20.0, span_count: 2, encumbrance: 1.5}\n"
    << "contact_wire: {linear_mass: " << kMuC << ", tension: " << kTc << "}\n"
    << "messenger: {linear_mass: 1.43, tension: 24500}\n"
    << "auxiliary_messenger: {linear_mass: " << kMuA << ", tension: " << kTa << ", height: " << kH << "}\n"
    << "droppers: {positions: [5.0, 15.0], axial_stiffness: 200000}\n"
    << "hangers: {positions: [2.5, 7.5, 12.5, 17.5], axial_stiffness: 200000}\n"
    << "contact: {rub_length: 0.0}\n"
    << "numerics: {element_length: " << element << "}\n";
  return y.str();
}

const cs::Dropper& at(const cs::Model& m, double x, bool hanger) {
  for (const cs::Dropper& d : m.droppers)
    if (std::fabs(d.x - x) < 1e-9 && d.hanger == hanger) return d;
  throw std::runtime_error("no dropper at " + std::to_string(x));
}

}  // namespace

// (a) The design rule against strings by hand. The contact wire, level (presag 0) at its
// supports and hangers, hangs on each hanger by the weight of half a spacing either side: 5 m of
// wire on an inner hanger (P_i), 3.75 m on one 2.5 m from a support (P_o). Between hangers it sags
// s_c = w_c 5^2 / (8 T_c) at the middle, where the droppers are (5, 15, 25, 35 m): there the
// auxiliary runs h above it, and at its anchors h above the held wire, s_c higher. Between
// droppers the auxiliary is a string under its weight w_a and the hangers: at the hanger 2.5 m
// from a dropper it sags M / T_a below its dropper points, M = (P_i + 5 w_a) 2.5 - w_a 2.5^2 / 2
// (a simply supported 10 m), which sets the hanger's length h - s_c - M / T_a. A dropper's force
// is its neighbouring segments' shares: at 15 m P_i + 5 w_a from 5-15 m and P_o + 5 w_a from the
// level 15-25 m; at 5 m P_i + 5 w_a and, from the anchor's segment, (P_o + 5 w_a) / 2 less the
// string's pull up toward the anchor s_c higher, T_a s_c / 5.
// Tolerance: the Hermite elements round a string's kink at a load over the elements beside it,
// an error first order in h (the stitched line's network test measures that order): 0.5 % of
// each force or sag at h = 0.05 m.
TEST(CompoundCatenary, DesignStaticsMatchStringsByHand) {
  const cs::Model m = cs::build_model(cs::load_scene_string(strings_yaml(0.05)));
  const double wc = kG * kMuC, wa = kG * kMuA;
  const double inner = wc * 5.0, outer = wc * 3.75;  // N, P_i and P_o
  EXPECT_NEAR(at(m, 7.5, true).static_tension, inner, 5e-3 * inner);
  EXPECT_NEAR(at(m, 12.5, true).static_tension, inner, 5e-3 * inner);
  EXPECT_NEAR(at(m, 2.5, true).static_tension, outer, 5e-3 * outer);
  EXPECT_NEAR(at(m, 17.5, true).static_tension, outer, 5e-3 * outer);
  const double sag_c = wc * 5.0 * 5.0 / (8.0 * kTc);
  const double moment = (inner + 5.0 * wa) * 2.5 - wa * 2.5 * 2.5 / 2.0;
  const double sag_a = moment / kTa;
  for (double x : {7.5, 12.5})
    EXPECT_NEAR(at(m, x, true).length, kH - sag_c - sag_a, 5e-3 * sag_a) << "hanger at " << x << " m";
  const double d15 = inner + outer + 10.0 * wa;
  const double d5 = inner + 5.0 * wa + 0.5 * (outer + 5.0 * wa) - kTa * sag_c / 5.0;
  EXPECT_NEAR(at(m, 15.0, false).static_tension, d15, 5e-3 * d15);
  EXPECT_NEAR(at(m, 5.0, false).static_tension, d5, 5e-3 * d5);
  EXPECT_NEAR(at(m, 35.0, false).static_tension, d5, 5e-3 * d5);  // the mirror image
}

namespace {

// The simple line and its compound twin whose auxiliary is (nearly) slack and weightless, with
// hangers at the droppers' stations and of the droppers' EA: in series a dropper of length L - h
// and a hanger of h are EA / L, the simple dropper of length L; the auxiliary's tension T_a adds
// a string of that tension beside the others, an effect of order T_a / T_c.
std::string limit_yaml(bool compound, double aux_tension) {
  std::ostringstream y;
  y << "name: limit\nline: {span_length: 50.0, span_count: 6, encumbrance: 1.5}\n"
    << "contact_wire: {linear_mass: 1.51, bending_stiffness: 276, tension: 14700, presag: 0.04}\n"
    << "messenger: {linear_mass: 1.43, bending_stiffness: 131.7, tension: 24500}\n"
    << "droppers: {positions: [5.0, 15.0, 25.0, 35.0, 45.0], axial_stiffness: 200000}\n"
    << "steady_arms: {stiffness: 2673.58}\nmessenger_supports: {stiffness: 500000}\n";
  if (compound)
    y << "auxiliary_messenger: {linear_mass: 1.0e-6, tension: " << aux_tension << ", height: 0.15}\n"
      << "hangers: {positions: [5.0, 15.0, 25.0, 35.0, 45.0], axial_stiffness: 200000}\n";
  return y.str();
}

std::vector<double> elasticity(const std::string& yaml, double x0, double x1) {
  const double F = 100.0;
  const cs::ElasticityProbe probe(cs::load_scene_string(yaml), F);
  std::vector<double> e;
  for (double x = x0; x <= x1 + 1e-9; x += 1.0) e.push_back(probe.uplift(x).at(0) / F);
  return e;
}

}  // namespace

// (b) The limit: as T_a falls the compound line's elasticity tends to the simple line's, in
// proportion to T_a. At T_a = 1 N (7e-5 of the contact wire's tension) within 1e-3 everywhere
// over a span; ten times the tension gives about ten times the difference (between 5 and 20).
TEST(CompoundCatenary, ASlackWeightlessAuxiliaryGivesTheSimpleLinesElasticity) {
  const double x0 = 150.0, x1 = 200.0;
  const std::vector<double> simple = elasticity(limit_yaml(false, 0.0), x0, x1);
  auto largest_change = [&](double tension) {
    const std::vector<double> e = elasticity(limit_yaml(true, tension), x0, x1);
    double worst = 0.0;
    for (std::size_t i = 0; i < e.size(); ++i) worst = std::max(worst, std::fabs(e[i] - simple[i]) / simple[i]);
    return worst;
  };
  const double slack = largest_change(1.0), tenfold = largest_change(10.0);
  EXPECT_LT(slack, 1e-3) << "T_a = 10 N: " << tenfold;
  EXPECT_GT(tenfold / slack, 5.0);
  EXPECT_LT(tenfold / slack, 20.0);
}

namespace {

// The compound reference line and the simple line of the same contact wire and messenger, the
// messenger also carrying the auxiliary's tension and mass, its droppers at the hangers' stations.
std::vector<std::string> simple_twin() {
  return {"auxiliary_messenger=none", "droppers.positions=[2.5,7.5,12.5,17.5,22.5,27.5,32.5,37.5,42.5,47.5]",
          "messenger.tension=39200", "messenger.linear_mass=2.79"};
}

double uniformity(const std::vector<double>& e) {  // (max - min) / (max + min), as EN 50119 states it
  const auto [lo, hi] = std::minmax_element(e.begin(), e.end());
  return (*hi - *lo) / (*hi + *lo);
}

}  // namespace

// (c) What the auxiliary is for (JR East: it "buffers the variation of the contact wire's
// stiffness along the span"): the compound line's elasticity is more uniform over a span than
// that of the simple line whose messenger takes the auxiliary's tension and weight.
TEST(CompoundCatenary, ElasticityIsMoreUniformOverTheSpan) {
  const double F = 100.0, x0 = 200.0, span = 50.0;
  const cs::ElasticityProbe compound(cs::load_scene_file(test_scenes::kCompound), F);
  const cs::ElasticityProbe simple(cs::load_scene_file(test_scenes::kCompound, simple_twin()), F);
  std::vector<double> ec, es;
  for (double x = x0; x <= x0 + span + 1e-9; x += 0.5) {
    ec.push_back(compound.uplift(x).at(0) / F);
    es.push_back(simple.uplift(x).at(0) / F);
  }
  EXPECT_LT(uniformity(ec), uniformity(es)) << uniformity(ec) << " against " << uniformity(es);
}

namespace {

// The amplitude (N) of the contact force's line nearest f over the analysis section: a direct
// Fourier sum of the mean-free force, the largest within half a resolution 1 / T either side.
double line_amplitude(const std::vector<double>& t, const std::vector<double>& f, double freq) {
  double mean = 0.0;
  for (double v : f) mean += v;
  mean /= static_cast<double>(f.size());
  const double T = t.back() - t.front();
  double best = 0.0;
  for (double q = freq - 0.5 / T; q <= freq + 0.5 / T + 1e-12; q += 0.05 / T) {
    std::complex<double> sum = 0.0;
    for (std::size_t i = 0; i < f.size(); ++i) sum += (f[i] - mean) * std::polar(1.0, -2.0 * M_PI * q * t[i]);
    best = std::max(best, 2.0 * std::abs(sum) / static_cast<double>(f.size()));
  }
  return best;
}

struct Lines {
  double span = 0.0, hanger = 0.0;  // N, at v / span and v / hanger spacing
};

Lines force_lines(const std::vector<std::string>& overrides) {
  cs::Simulation sim(cs::load_scene_file(test_scenes::kCompound, overrides));
  const cs::Model& m = sim.model();
  double x0 = 0.0, x1 = 0.0;
  cs::analysis_section(m, &x0, &x1);
  std::vector<double> t, f;
  while (!sim.finished()) {
    EXPECT_EQ(sim.step(), cs::StepStatus::kOk) << sim.status_message();
    if (sim.state().front < x0 || sim.state().front > x1) continue;
    t.push_back(sim.state().time);
    f.push_back(sim.state().pantograph_force_on(m, 0, 0));
  }
  const double v = m.scene.train_speed;
  return {line_amplitude(t, f, v / 50.0), line_amplitude(t, f, v / 5.0)};
}

}  // namespace

// (d) The contact force at speed (RTRI, Aboshi, Ikeda, Nagasaka: on compound lines its
// fluctuation is "small over each support span, comparatively large over each hanger span"):
// on the compound line the line at the hanger-passing frequency v / 5 m is stronger than the one
// at the span-passing v / 50 m, and the span-passing line is weaker than on the simple twin.
TEST(CompoundCatenary, ForceVariesAtTheHangersMoreThanAtTheSpans) {
  const Lines compound = force_lines({}), simple = force_lines(simple_twin());
  EXPECT_GT(compound.hanger, compound.span) << "span " << compound.span << " N, hanger " << compound.hanger << " N";
  EXPECT_LT(compound.span, simple.span);
}

// (e) The design state is an equilibrium: on every free wire node, the auxiliary's included, the
// constant load is balanced by the droppers' and hangers' design forces alone (round-off only).
TEST(CompoundCatenary, TheDesignStateIsAnEquilibrium) {
  const cs::Model m = cs::build_model(cs::load_scene_file(test_scenes::kCompound));
  ASSERT_GE(m.sections[0].auxiliary, 0);
  test_scenes::expect_design_equilibrium(m);
}

TEST(CompoundCatenary, BadInputIsRefusedByName) {
  const auto refused = test_scenes::expect_refused;
  const std::string y = strings_yaml(0.25);
  auto with = [&](const std::string& from, const std::string& to) {
    std::string s = y;
    EXPECT_NE(s.find(from), std::string::npos) << from;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  refused(with("height: 0.15", "height: 0"), "auxiliary_messenger.height");
  refused(with("height: 0.15", "height: 1.5"), "auxiliary_messenger.height");  // not below the messenger
  refused(with("tension: 14700, height", "tension: -1, height"), "auxiliary_messenger.tension");
  refused(with("height: 0.15", "height: 0.15, colour: red"), "auxiliary_messenger.colour");
  refused(with("auxiliary_messenger: {", "auxiliary_messenger: off\nx: {"), "auxiliary_messenger");
  refused(with("hangers: {positions: [2.5, 7.5, 12.5, 17.5], axial_stiffness: 200000}\n", ""), "auxiliary_messenger");
  refused(with("positions: [2.5, 7.5", "positions: [0.0, 7.5"), "hangers.positions");
  refused(with("positions: [2.5, 7.5", "positions: [7.5, 2.5"), "hangers.positions");
  refused(with("[2.5, 7.5, 12.5, 17.5], axial_stiffness: 200000", "[2.5], axial_stiffness: 0"), "hangers.axial_stiffness");
  refused(with("droppers: {positions: [5.0, 15.0], axial_stiffness: 200000}\n", ""), "auxiliary_messenger");
  refused(with("line: {", "contact_wire_count: 2\nline: {"), "contact_wire_count");
  refused(y + "stitch_wire: {length: 8.0, tension: 3500, linear_mass: 0.31}\n", "stitch_wire");
  refused(y + "stagger:\n  contact_wire: [0.2, -0.2]\nwind: {speed: 20, auxiliary_messenger: {diameter: 0.5}}\n",
          "wind.auxiliary_messenger.diameter");
  refused(with("line: {span_length: 20.0, span_count: 2, encumbrance: 1.5}", "line: {encumbrance: 1.5}") +
              "sections:\n  - {span_length: 20.0, span_count: 2, auxiliary_messenger: none,\n"
              "     hangers: {positions: [2.5], axial_stiffness: 200000}}\n",
          "sections[0].hangers");
  std::string no_aux = y;
  no_aux.erase(no_aux.find("auxiliary_messenger:"), no_aux.find("droppers:") - no_aux.find("auxiliary_messenger:"));
  refused(no_aux, "hangers");
}

// An auxiliary too slack for its hangers hangs below the contact wire: refused by its tension
// (the field, as scene fields are named: Python's SceneError.field reads it).
TEST(CompoundCatenary, AnAuxiliaryBelowTheContactWireIsRefused) {
  std::string y = strings_yaml(0.25);
  y.replace(y.find("tension: 14700, height"), 22, "tension: 50, height");
  try {
    cs::build_model(cs::load_scene_string(y));
    ADD_FAILURE() << "an auxiliary of 50 N was accepted";
  } catch (const cs::SceneError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("scene field 'auxiliary_messenger.tension' = 50 N: ", 0), 0u) << what;
    EXPECT_NE(what.find("auxiliary messenger hangs"), std::string::npos) << what;
  }
}

// The memory check before building counts the auxiliary and the hangers' stations.
TEST(CompoundCatenary, TheMemoryEstimateHoldsTheAuxiliary) {
  const cs::Model m = cs::build_model(cs::load_scene_file(test_scenes::kCompound));
  double nodes = 0.0;
  for (const cs::Wire& w : m.wires) nodes += w.nodes();
  EXPECT_GE(cs::estimate_model_bytes(m.scene) / cs::kModelBytesPerNode, nodes);
}

// The endless line carries the auxiliary like any wire of the block: the same 20 spans of pass,
// from station 1500 m, on the endless compound line and on a finite 60-span one whose anchors the
// window never reaches. They differ at the start by about 1e-4 N (the block's statics feel its
// anchors three spans away through the auxiliary, free through the supports). On this line such
// a difference does not stay small: the stiff short hangers go slack and snatch taut, and the
// force's detail depends on when. The finite line against itself with the uplift changed by
// 1e-7 N measures that: about 2 N rms of the 20 Hz force apart after 13 s, its std 0.5 %. So
// the endless pass must be no further from the finite one than twice that, and its 20 Hz mean
// and std within 1 % (as a window's statistics against the whole line's); a slip of the
// auxiliary or a hanger at the block's 21 moves would put a force step into each.
TEST(CompoundCatenary, TheEndlessBlockCarriesTheAuxiliary) {
  const std::vector<std::string> pass = {"train.start=1500", "train.end=2500", "numerics.preset=balanced",
                                         "numerics.window=auto"};
  std::vector<std::string> finite = pass, nudged = pass;
  finite.push_back("line.span_count=60");
  nudged.insert(nudged.end(), {"line.span_count=60", "pantographs.0.static_uplift=100.0000001"});
  cs::Simulation a(test_scenes::endless_scene(test_scenes::kCompound, pass));
  cs::Simulation b(cs::load_scene_file(test_scenes::kCompound, finite)), c(cs::load_scene_file(test_scenes::kCompound, nudged));
  ASSERT_TRUE(a.model().endless);
  ASSERT_GE(a.model().sections[0].auxiliary, 0);
  std::vector<double> fa, fb, fc;
  double offset_seen = 0.0;
  while (true) {
    const cs::StepStatus sa = a.step(), sb = b.step(), sc = c.step();
    ASSERT_EQ(sa, sb) << a.status_message() << " / " << b.status_message();
    ASSERT_EQ(sc, sb) << c.status_message();
    if (sa != cs::StepStatus::kOk) break;
    fa.push_back(cs::total_contact_force(a.model(), a.state(), 0));
    fb.push_back(cs::total_contact_force(b.model(), b.state(), 0));
    fc.push_back(cs::total_contact_force(c.model(), c.state(), 0));
    offset_seen = a.state().line_offset;
  }
  EXPECT_GT(offset_seen - a.model().initial_line_offset, 15 * 50.0);  // the block was moved along
  const double rate = 1.0 / a.model().dt;
  const std::vector<double> ga = cs::lowpass_zero_phase(fa, rate, 20.0), gb = cs::lowpass_zero_phase(fb, rate, 20.0),
                            gc = cs::lowpass_zero_phase(fc, rate, 20.0);
  auto mean_std = [](const std::vector<double>& f) {
    double s = 0.0, q = 0.0;
    for (double v : f) s += v, q += v * v;
    const double n = static_cast<double>(f.size());
    return std::make_pair(s / n, std::sqrt(q / n - s * s / n / n));
  };
  auto rms_apart = [](const std::vector<double>& x, const std::vector<double>& y) {
    double d2 = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) d2 += (x[i] - y[i]) * (x[i] - y[i]);
    return std::sqrt(d2 / static_cast<double>(x.size()));
  };
  const auto [ma, sa] = mean_std(ga);
  const auto [mb, sb] = mean_std(gb);
  EXPECT_NEAR(ma, mb, 1e-2 * mb);
  EXPECT_NEAR(sa, sb, 1e-2 * sb);
  const double endless = rms_apart(ga, gb), sensitivity = rms_apart(gc, gb);
  EXPECT_GT(sensitivity, 0.0);
  EXPECT_LT(endless, 2.0 * sensitivity) << "the finite line against itself nudged: " << sensitivity << " N";
}

// (g) On a 3-D line the auxiliary runs above the contact wire: held in plan at the contact wire's
// stagger at every support (vertically free there), the messenger above them both when its
// stagger is not given. Every wire of the strings' line is then held at the same points and
// loaded alike, so every dropper and hanger hangs plumb in the static state: no lean, to
// round-off (1e-9 m: the lateral statics' solve of stiffnesses 1e3-1e6 N/m).
TEST(CompoundCatenary, OnA3dLineTheAuxiliaryRunsAboveTheContactWire) {
  const double s = 0.2;
  cs::Simulation sim(cs::load_scene_string(strings_yaml(0.25) + "stagger:\n  contact_wire: [0.2, -0.2]\n"));
  const cs::Model& m = sim.model();
  ASSERT_TRUE(m.lateral);
  const cs::LateralModel& lat = *m.lateral;
  int hangers = 0, droppers = 0;
  for (const cs::LateralPendulum& p : lat.pendulums) {
    const cs::Dropper& d = m.droppers[p.dropper];
    EXPECT_NEAR(lat.calm[p.messenger], lat.calm[p.contact], 1e-9) << (d.hanger ? "hanger" : "dropper") << " at "
                                                                   << lat.node_x[p.contact];
    (d.hanger ? hangers : droppers) += 1;
  }
  EXPECT_EQ(hangers, 8);
  EXPECT_EQ(droppers, 4);
  // The messenger above the track centre: the droppers lean from it to the auxiliary, which the
  // supports keep at the contact wire's stagger and the stiff short hangers (S / l with l = 0.15 m
  // against the droppers' ~1.4 m) keep over the contact wire between them: each hanger leans
  // less than a tenth of the droppers' largest lean.
  cs::Simulation centred(cs::load_scene_string(strings_yaml(0.25) + "stagger:\n  contact_wire: [0.2, -0.2]\n  messenger: [0.0]\n"));
  const cs::Model& mc = centred.model();
  const cs::LateralModel& lc = *mc.lateral;
  double dropper_lean = 0.0, hanger_lean = 0.0;
  for (const cs::LateralPendulum& p : lc.pendulums) {
    const double lean = std::fabs(lc.calm[p.messenger] - lc.calm[p.contact]);
    double& largest = mc.droppers[p.dropper].hanger ? hanger_lean : dropper_lean;
    largest = std::max(largest, lean);
  }
  EXPECT_GT(dropper_lean, 0.05);
  EXPECT_LT(hanger_lean, 0.1 * dropper_lean);
  for (const cs::LateralSupport& sup : lc.supports) {
    if (!mc.wires[sup.wire].is_auxiliary_messenger) continue;
    EXPECT_NEAR(sup.stagger, std::fmod(sup.x, 40.0) < 1.0 ? s : -s, 1e-12) << "support at " << sup.x;
  }
}
