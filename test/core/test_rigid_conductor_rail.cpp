// Rigid overhead conductor rail (docs/rigid_conductor_rail.md): the profile with its clamped
// contact wire is a beam without tension on elastic supports. Its statics against the
// three-moment equation of a continuous beam, the elastic support against a beam on a central
// spring, a slow moving force against the statics, bad input, a pass over the reference scene,
// and on a 3-D line the profile in plan: its line through the stagger points, its swing, the
// steady wind's bending; a transition piece's varying stiffness against the force method.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "catenary_sim/core/engine/lateral_step.hpp"
#include "catenary_sim/core/engine/step.hpp"
#include "catenary_sim/core/model/build_model.hpp"
#include "catenary_sim/core/model/contact_geometry.hpp"
#include "catenary_sim/core/model/lateral.hpp"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/model/statics.hpp"
#include "catenary_sim/core/output/lateral_statistics.hpp"
#include "catenary_sim/core/output/pass_recorder.hpp"
#include "catenary_sim/core/scene/scene.hpp"
#include "catenary_sim/core/simulation.hpp"
#include "../support/quasi_static.hpp"
#include "../support/scene_refusal.hpp"
#include "../support/scenes.hpp"
#include "engine/lateral_workspace.hpp"  // (the joint solve's count of steps)

namespace cs = catenary_sim;

namespace {

constexpr double kRhoA = 7.27, kEI = 2.8e5, kG = 9.81, kSpan = 10.0;

// A one-section rigid rail of `spans` equal spans; `extra` is appended (pantographs, train, ...);
// lateral_ei > 0: the profile's own bending stiffness across the track.
std::string rail_yaml(int spans, double support_stiffness, double element, const std::string& extra = "",
                      double lateral_ei = 0.0) {
  std::ostringstream y;
  y.precision(10);
  y << "name: rail\n"
    << "line:\n  span_length: " << kSpan << "\n  span_count: " << spans << "\n"
    << "conductor_rail:\n  linear_mass: " << kRhoA << "\n  bending_stiffness: " << kEI
    << "\n  support_stiffness: " << support_stiffness << "\n";
  if (lateral_ei > 0.0) y << "  lateral_bending_stiffness: " << lateral_ei << "\n";
  y << "contact:\n  rub_length: 0.0\n"
    << "numerics:\n  element_length: " << element << "\n"
    << extra;
  return y.str();
}

// Support moments (sagging +) of a continuous beam of n equal spans L, pinned at both ends on
// rigid supports, by Clapeyron's three-moment equation (constant EI):
//   M_{i-1} + 4 M_i + M_{i+1} = -(r_left + r_right) / L,
// with r = q L^3 / 4 for a uniform load q on an adjacent span and 3 P L^2 / 8 for a point load P
// at its middle. rhs[i] for supports 1..n-1; the ends carry no moment. Thomas algorithm.
std::vector<double> three_moment(int n, const std::vector<double>& rhs) {
  std::vector<double> c(n + 1, 0.0), d(n + 1, 0.0), m(n + 1, 0.0);
  for (int i = 1; i < n; ++i) {
    const double denom = 4.0 - (i > 1 ? c[i - 1] : 0.0);
    c[i] = 1.0 / denom;
    d[i] = (rhs[i] - (i > 1 ? d[i - 1] : 0.0)) / denom;
  }
  for (int i = n - 1; i >= 1; --i) m[i] = d[i] - (i + 1 < n ? c[i] * m[i + 1] : 0.0);
  return m;
}

}  // namespace

// (a) Own-weight sag: the design statics hold the profile at the supports (the design height)
// and it sags between them as a continuous beam. Mid-span sag of span j from the three-moment
// solution: 5 q L^4 / (384 EI) + (M_j + M_{j+1}) L^2 / (16 EI) (an interior span of a long line
// tends to q L^4 / (384 EI)). Tolerance 0.5 %: beam
// elements give exact nodal values for nodal loads; the lumped load drops only the moment
// q h^2 / 12 at the two end nodes (the interior ones cancel), 1e-4 of the end span's moments.
TEST(RigidConductorRail, OwnWeightSagMatchesTheContinuousBeam) {
  const int n = 11;
  const cs::Model m = cs::build_model(cs::load_scene_string(rail_yaml(n, 5e6, 0.25)));
  ASSERT_EQ(m.contact_wires.size(), 1u);
  const cs::Wire& w = m.wires[m.contact_wires[0]];
  EXPECT_EQ(w.spec.tension, 0.0);
  const double q = kRhoA * kG, L = kSpan;
  const std::vector<double> M = three_moment(n, std::vector<double>(n + 1, -q * L * L / 2.0));
  const double H = m.scene.contact_wire_height;
  for (int j = 0; j < n; ++j) {
    EXPECT_NEAR(cs::lowest_design_height(m, j * L), H, 1e-9) << "support " << j;  // the design height at the supports
    const double sag = 5.0 * q * std::pow(L, 4) / (384.0 * kEI) + (M[j] + M[j + 1]) * L * L / (16.0 * kEI);
    EXPECT_NEAR(H - cs::lowest_design_height(m, (j + 0.5) * L), sag, 5e-3 * sag) << "span " << j;
  }
  // The middle span tends to the infinite beam's q L^4 / (384 EI): the pinned end's moment
  // deficit q L^2 / 12 decays by the factor -(2 - sqrt(3)) per support, so k supports from each
  // end it changes the middle sag by about 2 x 2 x 0.268^k: 0.6 % for the middle span of eleven
  // (k = 5); 1 % bounds it.
  const double infinite = q * std::pow(L, 4) / (384.0 * kEI);
  EXPECT_NEAR(H - cs::lowest_design_height(m, (n / 2 + 0.5) * L), infinite, 0.01 * infinite);
}

// (b) Point-load elasticity at mid-span, nearly rigid supports (1e9 N/m: the supports give under
// 1e-7 m against millimetres of bending): P L^3 / (48 EI) + (M_j + M_{j+1}) L^2 / (16 EI) with the
// three-moment support moments. Nodal values of beam elements are exact for a nodal point load
// and the probe's force is applied as given: 0.5 % covers the supports' give.
TEST(RigidConductorRail, MidSpanElasticityMatchesTheContinuousBeam) {
  const int n = 6;
  const double P = 100.0, L = kSpan;
  const cs::Scene scene = cs::load_scene_string(rail_yaml(n, 1e9, 0.25));
  const cs::ElasticityProbe probe(scene, P);
  for (int j : {1, 2, 3}) {
    std::vector<double> rhs(n + 1, 0.0);
    rhs[j] += -3.0 * P * L / 8.0;
    rhs[j + 1] += -3.0 * P * L / 8.0;
    const std::vector<double> M = three_moment(n, rhs);
    const double expected = P * L * L * L / (48.0 * kEI) + (M[j] + M[j + 1]) * L * L / (16.0 * kEI);
    const double up = probe.uplift((j + 0.5) * L).at(0);
    EXPECT_NEAR(up, expected, 5e-3 * expected) << "span " << j;
  }
}

// (a') The elastic support: two spans, held at the ends, a spring k at the middle support and the
// probe's force P on it. The beam over 2L is simply supported with a central spring:
// w = P / (k + 48 EI / (2L)^3), both terms of the same order here. Exact for the beam elements.
TEST(RigidConductorRail, ElasticSupportUnderPointLoadMatchesBeamOnSpring) {
  const double k = 2000.0, P = 100.0, L = kSpan;
  const cs::ElasticityProbe probe(cs::load_scene_string(rail_yaml(2, k, 0.25)), P);
  const double expected = P / (k + 48.0 * kEI / std::pow(2.0 * L, 3));
  EXPECT_NEAR(probe.uplift(L).at(0), expected, 1e-3 * expected);
}

// (c) A constant force moving slowly reproduces the static deflection under it. At 1 m/s the
// span's first mode (w1 ~ (pi/L)^2 sqrt(EI/rhoA) = 19 rad/s) sees the load at Omega = pi v / L
// = 0.31 rad/s: inertia adds (Omega/w1)^2 = 3e-4; Rayleigh alpha = 4 1/s lags the quasi-static
// response by alpha Omega / w1^2 = 0.3 % and damps the start transient (entering from a held end,
// ~ Omega/w1 = 2 % of the deflection) by exp(-alpha t / 2) < 1e-8 before the load reaches the
// checked span at t = 10 s. Tolerance 1 %.
TEST(RigidConductorRail, SlowMovingForceReproducesTheStaticDeflection) {
  const std::string extra =
      "damping:\n  alpha: 4.0\n"
      "pantographs:\n  - name: force\n    type: moving_force\n    static_uplift: 100.0\n"
      "train:\n  speed: 1.0\n  start: 0.0\n  end: 20.0\n";
  const cs::Scene scene = cs::load_scene_string(rail_yaml(4, 1e7, 0.5, extra));
  EXPECT_EQ(test_scenes::expect_quasi_static(scene, 100.0, 12.0, 1.0, 18.0, 0.01), 7);
}

// (d) Bad input is refused naming the field.
TEST(RigidConductorRail, BadInputIsRefusedByName) {
  const auto refused = test_scenes::expect_refused;
  std::string y = rail_yaml(3, 5e6, 0.25);
  auto with = [&](const std::string& from, const std::string& to) {
    std::string s = y;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  refused(with("bending_stiffness: 280000", "bending_stiffness: -1"), "conductor_rail.bending_stiffness");
  // Too soft to be a beam: 5 q L^4 / (384 EI) above L / 50 below 250 q L^3 / 384 = 46431 N m^2 here.
  const std::string soft = test_scenes::refusal_of_yaml(with("bending_stiffness: 280000", "bending_stiffness: 46000"));
  for (const char* word : {"conductor_rail.bending_stiffness", "46000", "at least 46431", "fiftieth"})
    EXPECT_NE(soft.find(word), std::string::npos) << soft;
  EXPECT_EQ(test_scenes::refusal_of_yaml(with("bending_stiffness: 280000", "bending_stiffness: 46500")), "");
  refused(with("linear_mass: 7.27", "linear_mass: 0"), "conductor_rail.linear_mass");
  refused(with("  support_stiffness: 5000000\n", ""), "conductor_rail.support_stiffness");
  refused(y + "messenger:\n  linear_mass: 1.0\n  tension: 10000\n", "messenger");
  refused(y + "droppers:\n  positions: [5.0]\n  axial_stiffness: 1e5\n", "droppers");
  refused(with("conductor_rail:\n", "conductor_rail:\n  tension: 1000\n"), "conductor_rail.tension");
  refused(with("span_count: 3", "span_count: 1"), "spans");
  // The window holds whole sections (test_window.cpp): lengths of its own are refused.
  refused(with("numerics:\n", "numerics:\n  window: {ahead: 100, behind: 100}\n"), "numerics.window");
  // The wind's drag on the profile: its height and coefficient in range, and drag blocks only for
  // the wires the line has (a rail-only line has no tensioned contact wire, a catenary no profile).
  refused(y + "stagger:\n  contact_wire: [0.2, -0.2]\nwind: {speed: 20, contact_wire: {diameter: 0.012}}\n",
          "wind.contact_wire");
  refused(y + "wind: {speed: 20, conductor_rail: {height: 0}}\n", "wind.conductor_rail.height");
  refused(y + "wind: {speed: 20, conductor_rail: {height: 0.6}}\n", "wind.conductor_rail.height");
  refused(y + "wind: {speed: 20, conductor_rail: {diameter: 0.1}}\n", "wind.conductor_rail.diameter");
  refused(y + "wind: {speed: 20, conductor_rail: {height: 0.11, drag_coefficient: 3.5}}\n",
          "wind.conductor_rail.drag_coefficient");
  refused(y + "wind: {speed: 20, messenger: {diameter: 0.0105}}\n", "wind.messenger");
  const std::string catenary = "name: c\nline: {spans: [50.0, 50.0]}\ncontact_wire: {linear_mass: 1.35, tension: 20000}\n";
  refused(catenary + "wind: {speed: 20, conductor_rail: {height: 0.11}}\n", "wind.conductor_rail");
  refused(catenary + "wind: {speed: 20, stitch_wire: {diameter: 0.0075}}\n", "wind.stitch_wire");
  refused(catenary + "wind: {speed: 20, auxiliary_messenger: {diameter: 0.0159}}\n", "wind.auxiliary_messenger");
  EXPECT_NO_THROW(cs::load_scene_string(y + "wind: {speed: 20, conductor_rail: {height: 0.11, drag_coefficient: 2.0}}\n"));
  refused(y + "imperfections:\n  contact_wire_wear:\n    section_loss: 0.1\n", "imperfections.contact_wire_wear");
  const std::string stagger = "stagger:\n  contact_wire: [0.2, -0.2]\n";
  std::string negative = rail_yaml(3, 5e6, 0.25, stagger, 1e5);
  negative.replace(negative.find("lateral_bending_stiffness: 100000"), 33, "lateral_bending_stiffness: -1");
  refused(negative, "conductor_rail.lateral_bending_stiffness");
  refused(rail_yaml(3, 5e6, 0.25, "", 1e5), "conductor_rail.lateral_bending_stiffness");  // a 2-D line
  // Across the track the same bound under the mean wind's drag q = 0.5 rho Cd h V^2 (a softer profile goes NaN):
  // at 10 m/s on the 0.11 m profile (Cd 2) q = 13.5 N/m, so at least 250 q L^3 / 384 = 8773 N m^2.
  const std::string windy = rail_yaml(3, 5e6, 0.25, stagger + "wind: {speed: 10}\n", 1.0);
  const std::string blown = test_scenes::refusal_of_yaml(windy);
  for (const char* word : {"conductor_rail.lateral_bending_stiffness", "at least 8772", "mean wind"})
    EXPECT_NE(blown.find(word), std::string::npos) << blown;
  EXPECT_EQ(test_scenes::refusal_of_yaml(rail_yaml(3, 5e6, 0.25, stagger + "wind: {speed: 10}\n", 8800.0)), "");
  // A span no allowed profile can take is the span's to shorten (the EI it would need is beyond the field's limit).
  std::string long_span = rail_yaml(3, 5e6, 0.25);
  long_span.replace(long_span.find("span_length: 10\n"), 16, "span_length: 500\n");
  refused(long_span, "line.spans");
  // Two rigid sections need the end ramp's rise.
  const std::string two =
      "name: two\nline: {}\nconductor_rail: {linear_mass: 7.27, bending_stiffness: 2.8e5, support_stiffness: 5e6}\n"
      "sections:\n  - {span_length: 10.0, span_count: 4}\n  - {span_length: 10.0, span_count: 4}\n"
      "overlap: {spans: 2}\n";
  refused(two, "overlap.support_rise");
  // A section that takes the top level's conductor_rail is a rail section: a catenary's part given
  // there alone is refused by its name (it replaced the profile's support spring, or hung the profile
  // from bridles); its own contact_wire makes it a catenary section.
  auto second = [](const std::string& part) {
    return "name: two\nline: {}\nconductor_rail: {linear_mass: 7.27, bending_stiffness: 2.8e5, support_stiffness: 5e6}\n"
           "sections:\n  - {span_length: 10.0, span_count: 4}\n  - {span_length: 10.0, span_count: 4" +
           (part.empty() ? "" : ", " + part) + "}\noverlap: {spans: 2, support_rise: 0.0}\n";
  };
  EXPECT_EQ(test_scenes::refusal_of_yaml(second("")), "");
  refused(second("steady_arms: {stiffness: 100}"), "sections[1].steady_arms");
  refused(second("steady_arms: {length: 1.15, linear_mass: 0.78, pull_off: 480}"), "sections[1].steady_arms");
  refused(second("bridle: {length: 8, tension: 5000, linear_mass: 0.31}"), "sections[1].bridle");
  refused(second("droppers: {positions: [5.0], axial_stiffness: 1e5}"), "sections[1].droppers");
  // A part the sections take from the top level is named there, not as the first section's.
  const std::string soft_top = test_scenes::refusal_of_yaml(second(""),
                                                            {"conductor_rail.bending_stiffness=1000"});
  EXPECT_NE(soft_top.find("'conductor_rail.bending_stiffness' = 1000"), std::string::npos) << soft_top;
  // A catenary section joined to a rigid one: the same end ramp is needed, and what the rail does
  // not model is refused for the whole line.
  const std::string mixed =
      "name: mixed\nline: {}\nconductor_rail: {linear_mass: 7.27, bending_stiffness: 2.8e5, support_stiffness: 5e6}\n"
      "sections:\n  - {span_length: 10.0, span_count: 4}\n"
      "  - {span_length: 10.0, span_count: 4, contact_wire: {linear_mass: 1.35, tension: 20000}}\n";
  refused(mixed + "overlap: {spans: 1}\n", "overlap.support_rise");
  refused(mixed + "overlap: {spans: 1, support_rise: 0.02}\nnumerics: {window: {ahead: 50, behind: 50}}\n", "numerics.window");
  // A tensioned wire without tension, set in code, is refused by validate().
  cs::Scene tensionless = cs::load_scene_string(
      "name: t\nline: {spans: [20.0]}\ncontact_wire: {linear_mass: 1.35, tension: 20000}\n");
  tensionless.sections[0].contact_wire.tension = 0.0;
  try {
    cs::validate(tensionless);
    ADD_FAILURE() << "a contact wire without tension was accepted";
  } catch (const cs::SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("contact_wire.tension"), std::string::npos) << e.what();
  }
}

// (e) A pass over the reference scene: it runs, stays bounded, the expansion joint shares the
// force, and the mean contact force over the analysis section is the static uplift (no aero
// term here). Bound 2 % (2.4 N): the roof spring (160 N/m) over the few millimetres the contact
// height varies along the rail gives about 1 N; the frame's momentum change over the ~7 s of the
// section (22.5 kg x a few cm/s) and its damper (100 N s/m x the mean vertical speed) well under 1 N.
TEST(RigidConductorRail, ReferencePassMeanForceIsTheUpliftAndTheJointSharesIt) {
  const cs::Scene scene = cs::load_scene_file(test_scenes::scene_path("rigid_conductor_rail.yaml"));
  cs::Simulation sim(scene);
  const cs::Model& m = sim.model();
  ASSERT_EQ(m.contact_wires.size(), 2u);
  double x0 = 0.0, x1 = 0.0;
  cs::analysis_section(m, &x0, &x1);
  double sum = 0.0, peak_u = 0.0;
  long count = 0;
  long shared_steps = 0, joint_steps = 0;
  double before_joint_on_second = 0.0, after_joint_on_first = 0.0;
  while (!sim.finished()) {
    ASSERT_EQ(sim.step(), cs::StepStatus::kOk) << sim.status_message();
    const cs::State& s = sim.state();
    const double x = s.front;
    const double f0 = s.pantograph_force_on(m, 0, 0), f1 = s.pantograph_force_on(m, 0, 1);
    if (x >= x0 && x <= x1) {
      sum += f0 + f1;
      ++count;
    }
    // Over the joint's middle span, 150-160 m, both profiles are at the design height.
    if (x > 150.0 && x < 160.0 && f0 > 0.0 && f1 > 0.0) shared_steps += 1;
    if (x > 150.0 && x < 160.0) ++joint_steps;
    if (x < 140.0) before_joint_on_second = std::max(before_joint_on_second, f1);
    if (x > 170.0) after_joint_on_first = std::max(after_joint_on_first, f0);
    peak_u = std::max(peak_u, s.u.head(m.n_catenary_dof).cwiseAbs().maxCoeff());
  }
  ASSERT_GT(count, 1000);
  const double uplift = scene.pantographs[0].net_uplift(scene.train_speed);
  EXPECT_NEAR(sum / count, uplift, 0.02 * uplift);
  // Shared over much of the middle span: both profiles sag alike there (each is held at 150 and
  // 160 m), so the head presses on both for more than a quarter of it (a loose bound: the
  // profiles' end ramps tilt them by a fraction of a millimetre against each other).
  ASSERT_GT(joint_steps, 0);
  EXPECT_GT(static_cast<double>(shared_steps) / joint_steps, 0.25);
  EXPECT_EQ(before_joint_on_second, 0.0);  // the second profile is not reached before the joint
  EXPECT_EQ(after_joint_on_first, 0.0);    // nor the first after it
  // Bounded: the profile moves by millimetres (the static elasticity is ~1e-5 m/N); 5 cm would
  // be a divergence, not a pass.
  EXPECT_LT(peak_u, 0.05);
}

// A catenary joined to the rail (config/catenary_to_rigid_rail.yaml): the open line's last span is
// the rail's first. The pantograph is handed over inside that joint: the rail is not touched
// before it, nor the contact wire after it, and the head stays on one of them throughout. On each
// side the pantograph's momentum balances: the mean contact force over the catenary's part and
// over the rail's equals the uplift less the roof spring's k3 times the lower frame's mean
// displacement from the start's, its damper's c3 times its mean velocity and the frame's momentum
// change over the part's time. 0.01 N: the explicit step samples the velocities half a step from
// the forces (dt 83 us: some 1e-3 N); a force lost or counted twice at the hand-over would be the
// uplift's share, tens of newtons. The same for the stitched open line
// (config/stitched_catenary_to_rigid_rail.yaml), whose portal support is left without a stitch
// wire.
namespace {

void expect_hand_over(const cs::Scene& scene) {
  cs::Simulation sim(scene);
  const cs::Model& m = sim.model();
  ASSERT_EQ(m.contact_wires.size(), 2u);
  ASSERT_FALSE(scene.sections[0].rigid);
  ASSERT_TRUE(scene.sections[1].rigid);
  const double joint0 = scene.sections[1].start, joint1 = scene.sections[0].end();
  ASSERT_LT(joint0, joint1);
  const cs::Pantograph& p = m.pantographs[0];
  const int lower = p.masses_count() - 1;
  const double uplift = scene.pantographs[0].net_uplift(scene.train_speed);
  struct Part {
    double x0 = 0.0, x1 = 0.0, force = 0.0, u = 0.0, v = 0.0, t0 = 0.0, t1 = 0.0;
    long n = 0;
    std::vector<double> v0, v1;
  };
  double x0 = 0.0, x1 = 0.0;
  cs::analysis_section(m, &x0, &x1);
  std::vector<Part> parts(2);
  parts[0].x0 = x0, parts[0].x1 = joint0;
  parts[1].x0 = joint1, parts[1].x1 = x1;
  double rail_before = 0.0, wire_after = 0.0, peak_u = 0.0;
  long lost = 0;
  // The pass starts in the static state with the pantograph pressing the wire: the roof spring
  // carries the uplift at the lower frame's displacement there.
  const double u_start = sim.state().pantograph_displacement(m, 0, lower);
  while (!sim.finished()) {
    ASSERT_EQ(sim.step(), cs::StepStatus::kOk) << sim.status_message();
    const cs::State& s = sim.state();
    const double x = s.front, fw = s.pantograph_force_on(m, 0, 0), fr = s.pantograph_force_on(m, 0, 1);
    if (x < joint0) rail_before = std::max(rail_before, fr);
    if (x > joint1) wire_after = std::max(wire_after, fw);
    if (x > x0 && x < x1 && fw + fr <= 0.0) ++lost;
    peak_u = std::max(peak_u, s.u.head(m.n_catenary_dof).cwiseAbs().maxCoeff());
    for (Part& part : parts) {
      if (x < part.x0 || x > part.x1) continue;
      std::vector<double> v(p.masses_count());
      for (int i = 0; i < p.masses_count(); ++i) v[i] = s.pantograph_velocity(m, 0, i);
      if (part.n == 0) part.v0 = v, part.t0 = s.time;
      part.v1 = v;
      part.t1 = s.time;
      part.force += fw + fr;
      part.u += s.pantograph_displacement(m, 0, lower);
      part.v += s.pantograph_velocity(m, 0, lower);
      ++part.n;
    }
  }
  EXPECT_EQ(rail_before, 0.0);
  EXPECT_EQ(wire_after, 0.0);
  EXPECT_EQ(lost, 0);
  EXPECT_LT(peak_u, 0.5);  // the contact wire rises by centimetres; half a metre would be a divergence
  for (const Part& part : parts) {
    ASSERT_GT(part.n, 1000) << part.x0;
    double momentum = 0.0;
    for (int i = 0; i < p.masses_count(); ++i) momentum += p.masses[i] * (part.v1[i] - part.v0[i]);
    const double expected = uplift - p.stiffness[lower] * (part.u / part.n - u_start) - p.damping[lower] * part.v / part.n -
                            momentum / (part.t1 - part.t0);
    EXPECT_NEAR(part.force / part.n, expected, 0.01) << "part from " << part.x0 << " m";
  }
}

}  // namespace

TEST(RigidConductorRail, ACatenaryJoinedToTheRailHandsThePantographOver) {
  expect_hand_over(cs::load_scene_file(test_scenes::scene_path("catenary_to_rigid_rail.yaml")));
  SCOPED_TRACE("stitched");
  expect_hand_over(cs::load_scene_file(test_scenes::scene_path("stitched_catenary_to_rigid_rail.yaml")));
}

// The stitched open line's stitch wires (stitch_wire.at_supports): one at each of the section's
// intermediate supports it names, 16 m long about it, carrying the droppers between its clamps;
// the portal's support (250 m) left out holds the dropper 4.5 m before it on the messenger. Every
// support named (the key left out), the portal's stitch wire reaches 8 m into the 12 m joint span,
// the section's end span, which holds its one clamp.
TEST(RigidConductorRail, AStitchedLineHasItsStitchWiresWhereTheSceneSaysAndNoneAtThePortal) {
  const std::string path = test_scenes::scene_path("stitched_catenary_to_rigid_rail.yaml");
  auto stitch_wires_and_the_portals_dropper = [](const cs::Model& m, std::vector<double>* middles) {
    int top = -1;
    for (const cs::Wire& w : m.wires) {
      if (!w.is_clamped_wire) continue;
      middles->push_back(0.5 * (w.x.front() + w.x.back()));
      EXPECT_NEAR(w.x.back() - w.x.front(), 16.0, 1e-9);
    }
    for (const cs::Dropper& d : m.droppers) {
      if (std::fabs(d.x - 245.5) > 1e-9) continue;
      for (std::size_t wi = 0; wi < m.wires.size(); ++wi)
        if (d.messenger_dof >= m.wires[wi].w_dof && d.messenger_dof < m.wires[wi].w_dof + m.wires[wi].nodes())
          top = static_cast<int>(wi);
    }
    return top;
  };
  std::vector<double> middles;
  const cs::Model shipped = cs::build_model(cs::load_scene_file(path));
  const int top = stitch_wires_and_the_portals_dropper(shipped, &middles);
  EXPECT_EQ(middles, (std::vector<double>{55.0, 110.0, 165.0, 220.0}));
  ASSERT_GE(top, 0);
  EXPECT_FALSE(shipped.wires[top].is_clamped_wire);
  middles.clear();
  const cs::Model every = cs::build_model(cs::load_scene_file(path, {"sections[0].stitch_wire.at_supports=null"}));
  const int every_top = stitch_wires_and_the_portals_dropper(every, &middles);
  EXPECT_EQ(middles, (std::vector<double>{55.0, 110.0, 165.0, 220.0, 250.0}));
  ASSERT_GE(every_top, 0);
  EXPECT_TRUE(every.wires[every_top].is_clamped_wire);
}

// An expansion joint of three spans holds both profiles at two shared supports: each of the two
// steady arms there gets a column of its own (a CSV with a name twice is refused by its readers).
TEST(RigidConductorRail, SharedSupportsOfAJointHaveColumnsOfTheirOwn) {
  const cs::Model m = cs::build_model(cs::load_scene_file(test_scenes::scene_path("rigid_conductor_rail.yaml")));
  const cs::PassRecorder rec(m);
  const std::vector<std::string> cols = rec.columns();
  const std::set<std::string> unique(cols.begin(), cols.end());
  EXPECT_EQ(unique.size(), cols.size());
  long arms = 0;
  for (const std::string& c : cols) arms += c.rfind("uplift_steady_arm", 0) == 0;
  EXPECT_EQ(arms, 31);  // 16 + 15 intermediate supports of the two sections
}

// Two pantographs 20 m apart on the rail (the same machinery as on a catenary): the pass runs and
// each pantograph's mean force over the analysis section is its static uplift, within the 2 % of
// the single pass (the trailing one meets a rail set moving by the leading one, a few newtons of
// oscillation that average out).
TEST(RigidConductorRail, TwoPantographsEachPressWithTheirUplift) {
  const cs::Scene scene = test_scenes::edited_scene("rigid_conductor_rail.yaml", [](YAML::Node& root) {
    YAML::Node second = YAML::Clone(root["pantographs"][0]);
    second["name"] = "trailing";
    second["position"] = 20.0;
    root["pantographs"].push_back(second);
  });
  cs::Simulation sim(scene);
  const cs::Model& m = sim.model();
  ASSERT_EQ(m.pantographs.size(), 2u);
  double x0 = 0.0, x1 = 0.0;
  cs::analysis_section(m, &x0, &x1);
  double sum[2] = {0.0, 0.0};
  long count[2] = {0, 0};
  while (!sim.finished()) {
    ASSERT_EQ(sim.step(), cs::StepStatus::kOk) << sim.status_message();
    const cs::State& s = sim.state();
    for (int p = 0; p < 2; ++p) {
      const double x = s.front - m.pantographs[p].position;
      if (x < x0 || x > x1) continue;
      sum[p] += s.pantograph_force_on(m, p, 0) + s.pantograph_force_on(m, p, 1);
      ++count[p];
    }
  }
  for (int p = 0; p < 2; ++p) {
    ASSERT_GT(count[p], 1000);
    const double uplift = scene.pantographs[p].net_uplift(scene.train_speed);
    EXPECT_NEAR(sum[p] / count[p], uplift, 0.02 * uplift) << scene.pantographs[p].name;
  }
}

// (f) A 3-D line: the profile held at its stagger at every support, with no tension and nothing
// across the track to load it, takes the static line of a continuous beam forced through the
// stagger points. For the zigzag +-s on equal spans L every support is a mirror plane (its
// neighbours on both sides at the other stagger), so the slope is 0 there and each span is the
// cubic y = s_a + (s_b - s_a)(3 xi^2 - 2 xi^3), whose shear 12 EI (s_b - s_a) / L^3 changes sign
// at each support: a pull-off of 24 EI |s_b - s_a| / L^3 = 48 EI s / L^3, toward the track centre.
// The pinned ends disturb this by 2 - sqrt(3) = 0.27 per span (the three-moment equation's
// decay): 0.27^14 = 1e-8 of it at the middle spans of 30. Beam elements hold a cubic exactly, so
// what is left is round-off: 1e-9 m on the line, 1e-6 of the pull-off.
namespace {

void zigzag_bends_as_a_continuous_beam(double lateral_ei) {
  const double s = 0.2, ei = lateral_ei > 0.0 ? lateral_ei : kEI;
  const cs::Scene scene = cs::load_scene_string(rail_yaml(30, 5e6, 0.25, "stagger:\n  contact_wire: [0.2, -0.2]\n", lateral_ei));
  cs::Simulation sim(scene);
  const cs::Model& m = sim.model();
  ASSERT_TRUE(m.lateral);
  const cs::LateralModel& lat = *m.lateral;
  ASSERT_EQ(lat.wires.size(), 1u);
  const cs::Wire& w = lat.wires[0];
  int checked = 0;
  for (int i = 0; i < w.nodes(); ++i) {
    if (w.x[i] < 140.0 - 1e-9 || w.x[i] > 160.0 + 1e-9) continue;  // spans 14 and 15
    const int span = std::min(15, static_cast<int>(std::floor(w.x[i] / kSpan + 1e-9)));
    const double sa = span % 2 ? -s : s, sb = -sa, xi = w.x[i] / kSpan - span;
    EXPECT_NEAR(lat.calm[w.w_dof + i], sa + (sb - sa) * (3 * xi * xi - 2 * xi * xi * xi), 1e-9) << "x " << w.x[i];
    ++checked;
  }
  EXPECT_EQ(checked, 81);  // 0.25 m elements over 20 m
  const double pull_off = 48.0 * ei * s / (kSpan * kSpan * kSpan);  // 2688 N with the vertical EI
  int supports = 0;
  for (const cs::LateralSupport& sup : lat.supports) {
    if (sup.x < 120.0 - 1e-9 || sup.x > 180.0 + 1e-9) continue;
    EXPECT_NEAR(std::fabs(sup.pull_off), pull_off, 1e-6 * pull_off) << "support at " << sup.x;
    EXPECT_LT(sup.pull_off * sup.stagger, 0.0) << "support at " << sup.x;  // toward the centre
    ++supports;
  }
  EXPECT_EQ(supports, 7);
}

}  // namespace

TEST(RigidConductorRail, OnA3dLineAZigzagBendsTheProfileAsAContinuousBeam) {
  // With the vertical EI across the track too, and with a lateral EI of its own (half: the line is
  // the same cubic, the pull-off half).
  for (const double lateral_ei : {0.0, 0.5 * kEI}) {
    SCOPED_TRACE(lateral_ei > 0.0 ? "lateral EI of its own" : "the vertical EI");
    zigzag_bends_as_a_continuous_beam(lateral_ei);
  }
}

// (g) Nothing joins a rail's two planes: no droppers lean, no hinged arm turns, and the strip is
// flat across its working width. So on a 3-D line (rigid_conductor_rail_3d.yaml, the reference
// scene with a stagger) the vertical pass is the 2-D line's, to the bit, while the contact point
// runs across the strip between the staggers: +-0.2 m at the supports, where the slope is 0 by
// symmetry (within 0.1 mm at the steps nearest them). On one profile it moves at the train's
// speed times the profile's slope in plan, which a beam through the stagger points keeps within
// 1.5x its chords' 0.01: under 3 x 0.01 x 33.3 m/s = 1 m/s, where a hand-over between the
// joint's two profiles would jump at some 50 m/s.
TEST(RigidConductorRail, OnA3dLineTheVerticalPassIsThe2dLinesAndTheContactPointFollowsTheStagger) {
  cs::Simulation flat(cs::load_scene_file(test_scenes::scene_path("rigid_conductor_rail.yaml")));
  cs::Simulation staggered(cs::load_scene_file(test_scenes::scene_path("rigid_conductor_rail_3d.yaml")));
  ASSERT_FALSE(flat.model().lateral);
  ASSERT_TRUE(staggered.model().lateral);
  cs::LateralRecorder recorder(staggered.model());
  recorder.record(staggered.model(), staggered.state());
  double lowest = 1.0, highest = -1.0;
  long steps = 0;
  while (!flat.finished() && !staggered.finished()) {
    ASSERT_EQ(flat.step(), cs::StepStatus::kOk);
    ASSERT_EQ(staggered.step(), cs::StepStatus::kOk);
    recorder.record(staggered.model(), staggered.state());
    ++steps;
    ASSERT_TRUE(flat.state().u == staggered.state().u) << "step " << steps;
    ASSERT_TRUE(flat.state().v == staggered.state().v) << "step " << steps;
    for (double y : staggered.state().lateral.contact_lateral)
      if (!std::isnan(y)) {
        lowest = std::min(lowest, y);
        highest = std::max(highest, y);
      }
  }
  EXPECT_TRUE(flat.finished() && staggered.finished());
  EXPECT_GT(steps, 100000);
  EXPECT_NEAR(lowest, -0.2, 1e-4);
  EXPECT_NEAR(highest, 0.2, 1e-4);
  const cs::LateralStatistics stats = recorder.statistics(staggered.model(), staggered.state());
  ASSERT_EQ(stats.contacts.size(), 1u);
  EXPECT_GT(stats.contacts[0].sweep_max, 0.1);
  EXPECT_LT(stats.contacts[0].sweep_max, 1.0);
}

// (h) Moved from its static line the profile's lateral plane swings. Plucked in the span mode of
// a continuous beam on equal spans held at every support (sin(pi x / L) in each span, the sign
// alternating, so that each support sees the same slope on both sides; the pinned ends too), it
// swings at a simply supported span's frequency omega = pi^2 / L^2 sqrt(EI / m) = 19.4 rad/s
// (3.1 Hz), whatever the stagger it swings about. Tolerance 0.1 %: the elements (40 to a span)
// shift so long a mode by well under 1e-4, the step ((omega dt)^2 / 24, omega dt = 2e-3) and the
// light Rayleigh damping (xi = 1.3e-3, the damped frequency lower by xi^2 / 2) by under 1e-6; the
// period is read from zero crossings interpolated within a step over 5 periods.
// With a lateral EI of its own (conductor_rail.lateral_bending_stiffness, here half the vertical
// one) the profile swings at pi^2 / L^2 sqrt(EI_lateral / m), a factor 1 / sqrt(2) lower, in the
// generic lateral step (the fused sweep runs on the vertical band).
namespace {

void plucked_profile_swings_at_its_span_frequency(double lateral_ei) {
  const double amplitude = 1e-3, ei = lateral_ei > 0.0 ? lateral_ei : kEI;
  const std::string extra =
      "stagger:\n  contact_wire: [0.2, -0.2]\n"
      "pantographs:\n  - name: force\n    type: moving_force\n    static_uplift: 100.0\n"
      "train:\n  speed: 1.0\n  start: 0.0\n  end: 25.0\n";
  cs::Simulation sim(cs::load_scene_string(rail_yaml(6, 5e6, 0.25, extra, lateral_ei)));
  const cs::Model& m = sim.model();
  ASSERT_TRUE(m.lateral && !m.lateral->windy && m.lateral->pendulums.empty() && m.lateral->registrations.empty());
  EXPECT_EQ(m.lateral->planes.empty(), lateral_ei > 0.0);
  const cs::LateralModel& lat = *m.lateral;
  const cs::Wire& w = lat.wires[0];
  cs::State s = sim.state();
  for (int i = 0; i < w.nodes(); ++i) {
    const int span = std::min(5, static_cast<int>(std::floor(w.x[i] / kSpan + 1e-9)));
    s.lateral.y[w.w_dof + i] += (span % 2 ? -1.0 : 1.0) * amplitude * std::sin(M_PI * (w.x[i] / kSpan - span));
  }
  int probe = 0;  // mid-span of span 2
  while (w.x[probe] < 25.0 - 1e-9) ++probe;
  const int dof = w.w_dof + probe;
  std::vector<double> up_crossings;
  double before = s.lateral.y[dof] - lat.initial[dof];
  while (s.time < 2.0 * std::sqrt(kEI / ei)) {  // (6 periods)
    ASSERT_EQ(cs::step(m, s), cs::StepStatus::kOk);
    const double now = s.lateral.y[dof] - lat.initial[dof];
    if (before < 0.0 && now >= 0.0) up_crossings.push_back(s.time - m.dt * now / (now - before));
    before = now;
  }
  ASSERT_GE(up_crossings.size(), 5u);
  const double period = (up_crossings.back() - up_crossings.front()) / (up_crossings.size() - 1);
  const double omega = M_PI * M_PI / (kSpan * kSpan) * std::sqrt(ei / kRhoA);
  EXPECT_NEAR(2.0 * M_PI / period, omega, 0.001 * omega) << "period " << period << " s";
}

}  // namespace

TEST(RigidConductorRail, OnA3dLineAPluckedProfileSwingsAtItsSpanFrequency) {
  for (const double lateral_ei : {0.0, 0.5 * kEI}) {
    SCOPED_TRACE(lateral_ei > 0.0 ? "lateral EI of its own" : "the vertical EI");
    plucked_profile_swings_at_its_span_frequency(lateral_ei);
  }
}

// (i) A steady cross wind on a 3-D rail: the profile, held at every support, takes the drag
// q = 0.5 rho Cd h V^2 per metre on the height h it shows the wind (wind.conductor_rail). On equal
// spans every interior support is a mirror plane of the load, so the slope is 0 there and each
// span bends as a beam clamped at both ends: y = q L^4 / (24 EI) xi^2 (1 - xi)^2, q L^4 / (384 EI)
// at mid-span (11 mm here), and each support takes q L more, downwind. The load is lumped on the nodes, q h
// on each; on equal elements that is the consistent load at every node inside the wire (the
// elements' end moments q h^2 / 12 cancel), and beam elements are exact at their nodes under a
// consistent load, so what is left is the pinned ends' disturbance, 0.27 per span (0.27^14 = 1e-8
// at the middle of 30), and round-off: 1e-9 m on the line, 1e-6 of the supports' q L. With a
// lateral EI of its own (half) the blow-off doubles and the supports' share stays q L.
// Nothing else acts sideways, so a pass keeps the profile on that line (1e-9 m): the step's drag
// is the statics'.
namespace {

void steady_wind_bends_the_profile_as_a_clamped_span(double lateral_ei) {
  const double speed = 30.0, rho = 1.225, height = 0.11, cd = 2.0, ei = lateral_ei > 0.0 ? lateral_ei : kEI;
  std::ostringstream wind;
  wind << "wind:\n  speed: " << speed << "\n  conductor_rail: {height: " << height << ", drag_coefficient: " << cd << "}\n"
       << "pantographs:\n  - name: force\n    type: moving_force\n    static_uplift: 100.0\n"
       << "train:\n  speed: 30.0\n  start: 130.0\n  end: 170.0\n";
  cs::Simulation sim(cs::load_scene_string(rail_yaml(30, 5e6, 0.25, wind.str(), lateral_ei)));
  const cs::Model& m = sim.model();
  ASSERT_TRUE(m.lateral && m.lateral->windy);
  const cs::LateralModel& lat = *m.lateral;
  ASSERT_EQ(lat.wires.size(), 1u);
  const cs::Wire& w = lat.wires[0];
  const double q = 0.5 * rho * cd * height * speed * speed;  // 121 N/m, toward +y
  int checked = 0;
  for (int i = 0; i < w.nodes(); ++i) {
    if (w.x[i] < 140.0 - 1e-9 || w.x[i] > 160.0 + 1e-9) continue;  // spans 14 and 15
    const double xi = w.x[i] / kSpan - std::floor(w.x[i] / kSpan + 1e-9);
    const double expected = q * std::pow(kSpan, 4) / (24.0 * ei) * xi * xi * (1 - xi) * (1 - xi);
    EXPECT_NEAR(lat.initial[w.w_dof + i] - lat.calm[w.w_dof + i], expected, 1e-9) << "x " << w.x[i];
    ++checked;
  }
  EXPECT_EQ(checked, 81);
  int supports = 0;
  for (const cs::LateralSupport& sup : lat.supports) {
    if (sup.x < 120.0 - 1e-9 || sup.x > 180.0 + 1e-9) continue;
    // (pull_off: the profile's force on the support, here downwind)
    EXPECT_NEAR(sup.pull_off_wind - sup.pull_off, q * kSpan, 1e-6 * q * kSpan) << "support at " << sup.x;
    ++supports;
  }
  EXPECT_EQ(supports, 7);
  cs::State s = sim.state();
  cs::StepStatus status = cs::StepStatus::kOk;
  while (s.front < 170.0 && status == cs::StepStatus::kOk) status = cs::step(m, s);
  ASSERT_EQ(status, cs::StepStatus::kOk);
  double off = 0.0;
  for (int i = 0; i < lat.n; ++i) off = std::max(off, std::fabs(s.lateral.y[i] - lat.initial[i]));
  EXPECT_LT(off, 1e-9);
}

}  // namespace

TEST(RigidConductorRail, OnA3dLineASteadyWindBendsEachSpanAsAClampedBeam) {
  for (const double lateral_ei : {0.0, 0.5 * kEI}) {
    SCOPED_TRACE(lateral_ei > 0.0 ? "lateral EI of its own" : "the vertical EI");
    steady_wind_bends_the_profile_as_a_clamped_span(lateral_ei);
  }
}

// On a 3-D line in wind, the vertical step's solve of each section's profile takes the profile's
// lateral plane along in a second lane (LateralModel::centred_joint_twin, step.cpp). Each lane does
// its own plane's IEEE operations with its own factors, and the lateral forces it solves with (the
// load, the drag of the wind at the step's start, the supports' springs) read nothing the vertical
// step changes, so the pass must be that of the two planes' solves one after the other (a copy of
// the model without the joint factors) to the bit: in a turbulent cross wind (the wind refreshed
// at each step's start either way) with the profile's vertical EI across the track, and with a
// lateral EI of its own (the lanes' factors differ). A lateral plane leaving the divergence limit
// is reported as the lateral plane's, at the same step and node.
namespace {

// Steps `scene` with the joint solve and a copy of its model without it side by side; every value
// of both planes, the status and a lateral divergence's node must agree. Returns the steps taken,
// and the last step's status in `last`.
int expect_joint_solve_is_two_solves(const cs::Scene& scene, cs::StepStatus* last) {
  cs::Simulation joint(scene);
  const cs::Model& m = joint.model();
  EXPECT_TRUE(m.lateral);
  if (!m.lateral) return 0;
  EXPECT_FALSE(m.lateral->centred_joint_twin.empty());
  cs::Model apart = m;
  auto lat = std::make_shared<cs::LateralModel>(*apart.lateral);
  lat->centred_joint_twin.clear();
  lat->centred_joint_single.clear();
  apart.lateral = lat;
  cs::State a = joint.state();
  int steps = 0;
  while (true) {
    const cs::StepStatus sj = joint.step();
    const cs::StepStatus sa = cs::step(apart, a);
    const cs::State& j = joint.state();
    EXPECT_EQ(sj, sa);
    EXPECT_EQ(j.lateral.diverged, a.lateral.diverged);
    EXPECT_EQ(j.lateral.diverged_node, a.lateral.diverged_node);
    EXPECT_EQ(j.diverged_dof, a.diverged_dof);
    *last = sj;
    if (sj != cs::StepStatus::kOk || sa != cs::StepStatus::kOk) break;
    ++steps;
    for (int i = 0; i < m.n_dof; ++i)
      if (j.u[i] != a.u[i] || j.v[i] != a.v[i]) {
        ADD_FAILURE() << "DOF " << i << " step " << steps << ": u " << j.u[i] << " / " << a.u[i];
        return steps;
      }
    for (int i = 0; i < m.lateral->n; ++i)
      if (j.lateral.y[i] != a.lateral.y[i] || j.lateral.v[i] != a.lateral.v[i]) {
        ADD_FAILURE() << "lateral node " << i << " step " << steps << ": y " << j.lateral.y[i] << " / " << a.lateral.y[i];
        return steps;
      }
  }
  // Every step taken solved both planes at once, the one that left the limit too.
  EXPECT_EQ(joint.state().lateral.work->joined_steps, steps + (*last == cs::StepStatus::kDiverged ? 1 : 0));
  return steps;
}

}  // namespace

TEST(RigidConductorRail, OnA3dLineInWindOneSolveOfBothPlanesIsTheTwoSolvesBitForBit) {
  const std::vector<std::string> wind = {"sections[0].span_count=5", "sections[1].span_count=5", "wind.speed=30",
                                         "wind.turbulence.intensity=0.15", "wind.turbulence.length_scale=50",
                                         "wind.turbulence.seed=1"};
  const std::string path = test_scenes::scene_path("rigid_conductor_rail_3d.yaml");
  cs::StepStatus last = cs::StepStatus::kOk;
  EXPECT_GT(expect_joint_solve_is_two_solves(cs::load_scene_file(path, wind), &last), 20000);
  EXPECT_EQ(last, cs::StepStatus::kFinished);
  std::vector<std::string> own_ei = wind;
  own_ei.push_back("conductor_rail.lateral_bending_stiffness=1.4e5");
  EXPECT_GT(expect_joint_solve_is_two_solves(cs::load_scene_file(path, own_ei), &last), 20000);
  EXPECT_EQ(last, cs::StepStatus::kFinished);
  // The stagger (0.2 m) and the first span's gusty blow-off reach 0.21 m after some 2 s.
  std::vector<std::string> beyond = wind;
  beyond.push_back("numerics.divergence_limit=0.21");
  EXPECT_GT(expect_joint_solve_is_two_solves(cs::load_scene_file(path, beyond), &last), 100);
  EXPECT_EQ(last, cs::StepStatus::kDiverged);
}

// (j) A transition piece (conductor_rail.transition_piece) where a catenary joins the rail: over
// `length` from the profile's end its EI rises linearly from end_bending_stiffness to the
// profile's. The profile alone on rigid supports (its statics with every support held) against the
// force method for a continuous beam of varying EI, pinned at both ends: the interior support
// moments M_j are the redundants, from the flexibilities f_ij = int m_i m_j / EI and the load's
// terms d_i = int m_i M0 / EI (M0: the point load P on the simply supported spans, m_i: a unit
// moment at support i); the deflection under the load is int M M0 / (P EI) with
// M = M0 + sum M_j m_j (the reduction theorem). Simpson's rule on 4000 intervals a span, every
// kink of EI and M0 on an even grid point: 1e-9 of the result.
// The model takes each element's EI at its middle; over an element of h = 0.25 m that changes its
// compliance by h^2 / 12 (EI' / EI)^2, 1.9e-3 at the softest end (EI' / EI = 0.6 / m) and falling
// as EI rises, a bound the deflection's weighted average stays under. Tolerance 2e-3. The piece
// makes the end span's deflection some 40 % larger, far outside it.
namespace {

double continuous_beam_deflection(int n, double L, const std::function<double(double)>& ei, double P, double xp) {
  const int per = 4000, N = n * per;
  const double h = L / per;
  const int k = static_cast<int>(std::floor(xp / L));
  const double a = xp - k * L;
  auto m0 = [&](double x) {  // the load on the simply supported span k
    if (x < k * L || x > (k + 1) * L) return 0.0;
    const double xi = x - k * L;
    return xi <= a ? P * (L - a) * xi / L : P * a * (L - xi) / L;
  };
  auto unit = [&](int i, double x) {  // a unit moment at interior support i
    const double xi = x - (i - 1) * L;
    if (xi < 0.0 || xi > 2.0 * L) return 0.0;
    return xi <= L ? xi / L : 2.0 - xi / L;
  };
  auto integrate = [&](const std::function<double(double)>& g) {
    double sum = 0.0;
    for (int j = 0; j <= N; ++j) sum += (j == 0 || j == N ? 1.0 : (j % 2 ? 4.0 : 2.0)) * g(j * h) / ei(j * h);
    return sum * h / 3.0;
  };
  const int r = n - 1;
  Eigen::MatrixXd f(r, r);
  Eigen::VectorXd d(r);
  for (int i = 1; i <= r; ++i) {
    for (int j = 1; j <= r; ++j) f(i - 1, j - 1) = integrate([&](double x) { return unit(i, x) * unit(j, x); });
    d(i - 1) = integrate([&](double x) { return unit(i, x) * m0(x); });
  }
  const Eigen::VectorXd moments = f.ldlt().solve(-d);
  return integrate([&](double x) {
    double m = m0(x);
    for (int i = 1; i <= r; ++i) m += moments(i - 1) * unit(i, x);
    return m * m0(x) / P;
  });
}

// The deflection of a model's rail profile (its first contact wire) under P at station xp, every
// support held (the profile's band alone: the supports' springs and the catenary left out).
double profile_deflection(const cs::Model& m, double P, double xp) {
  const cs::Wire& w = m.wires[m.contact_wires[0]];
  int node = 0;
  while (w.x[node] < xp - 1e-9) ++node;
  std::vector<double> load(w.nodes(), 0.0), height, slope, reactions;
  load[node] = -P;
  cs::solve_wire_statics(w, load, w.support_nodes, std::vector<double>(w.support_nodes.size(), 0.0), height, slope,
                         reactions);
  return -height[node];
}

// The rail (4 spans, 0-40 m) joined at its end by a catenary section over one span (30-40 m).
std::string rail_then_catenary(const std::string& piece) {
  return "name: joined\nline: {}\n"
         "conductor_rail: {linear_mass: 7.27, bending_stiffness: 2.8e5, support_stiffness: 5e6" +
         (piece.empty() ? std::string() : ", transition_piece: " + piece) +
         "}\nnumerics: {element_length: 0.25}\nsections:\n  - {span_length: 10.0, span_count: 4}\n"
         "  - {span_length: 10.0, span_count: 4, contact_wire: {linear_mass: 1.35, tension: 20000}}\n"
         "overlap: {spans: 1, support_rise: 0.02}\n";
}

}  // namespace

TEST(RigidConductorRail, ATransitionPieceSoftensTheProfilesEndAsABeamOfVaryingStiffness) {
  const int n = 4;
  const double P = 100.0, L = kSpan, length = 5.0, end_ei = 0.25 * kEI;
  const cs::Model with = cs::build_model(cs::load_scene_string(rail_then_catenary("{length: 5.0, end_bending_stiffness: 70000}")));
  const cs::Model without = cs::build_model(cs::load_scene_string(rail_then_catenary("")));
  auto piece_ei = [&](double x) {
    const double s = n * L - x;  // from the profile's end at the joint (its start meets no catenary)
    return s < length ? end_ei + (kEI - end_ei) * s / length : kEI;
  };
  for (const double x : {38.75, 37.5, 35.0, 25.0, 5.0}) {
    const double expected = continuous_beam_deflection(n, L, piece_ei, P, x);
    EXPECT_NEAR(profile_deflection(with, P, x), expected, 2e-3 * expected) << "x " << x;
    const double uniform = continuous_beam_deflection(n, L, [](double) { return kEI; }, P, x);
    EXPECT_NEAR(profile_deflection(without, P, x), uniform, 2e-3 * uniform) << "x " << x;
    if (x > 37.0) {
      EXPECT_GT(expected, 1.2 * uniform) << "x " << x;  // what the piece is for
    }
  }
  // On a 3-D line with a lateral EI of its own the piece softens the profile across the track in
  // the same proportion: every element's lateral stiffness is its vertical one times
  // EI_lateral / EI (1e-12: the same products in another order).
  std::string plan = rail_then_catenary("{length: 5.0, end_bending_stiffness: 70000}");
  plan.insert(plan.find(", support_stiffness"), ", lateral_bending_stiffness: 140000");
  const cs::Model m3 = cs::build_model(cs::load_scene_string(plan + "stagger:\n  contact_wire: [0.2, -0.2]\n"));
  ASSERT_TRUE(m3.lateral);
  const int rail = m3.contact_wires[0];
  const cs::Wire& vertical = m3.wires[rail];
  const cs::Wire& lateral = m3.lateral->wires[rail];
  ASSERT_EQ(vertical.e_ww.size(), lateral.e_ww.size());
  for (std::size_t e = 0; e < vertical.e_ww.size(); ++e)
    EXPECT_NEAR(lateral.e_ww[e] / vertical.e_ww[e], 0.5, 1e-12) << "element " << e;
  EXPECT_NEAR(vertical.e_ww.back() / vertical.e_ww.front(), 0.25 + 0.75 * 0.125 / length, 1e-12);
  // Bad input, by name.
  const auto refused = test_scenes::expect_refused;
  // (read where it is given, the top level; checked against the section it went to)
  const std::string f = "conductor_rail.transition_piece";
  // (The piece is the top level's conductor_rail's: named there, not as the first section's.)
  refused(rail_then_catenary("{length: 5.0, end_bending_stiffness: 3e5}"), "'" + f + ".end_bending_stiffness'");
  refused(rail_then_catenary("{length: 0, end_bending_stiffness: 7e4}"), f + ".length");
  refused(rail_then_catenary("{length: 12, end_bending_stiffness: 7e4}"), "'" + f + ".length'");
  // (Bounded by the end span alone, as the scene reference says: no cap of its own below it.)
  const std::string long_piece = test_scenes::refusal_of_yaml(rail_then_catenary("{length: 60, end_bending_stiffness: 7e4}"));
  EXPECT_NE(long_piece.find("within the end span"), std::string::npos) << long_piece;
  refused(rail_then_catenary("{length: 5.0}"), f + ".end_bending_stiffness");
  // The softened end span holds its sag below a fiftieth of it as every span does, its EI rising
  // over the piece. On this profile, whose 10 m span sags a sixth of that at its full EI, any end
  // holds: M / EI stays finite where the piece's EI and the moment both vanish at the held end.
  EXPECT_EQ(test_scenes::refusal_of_yaml(rail_then_catenary("{length: 10, end_bending_stiffness: 1}")), "");
  // On a profile 2 % above the least EI for its spans (250 q L^3 / 384), the named least end EI is
  // accepted 1 % above and refused 1 % below (the bisection's and the integration's errors are
  // far smaller), it lies below that least EI (a piece ending there is nowhere softer than a
  // uniform span that holds) and a shorter piece may end softer.
  const double q = 7.27 * 9.81, least_uniform = 250.0 * q * 1000.0 / 384.0;
  auto stiff_enough_only = [&](double piece_length, double end_ei) {
    std::string y = rail_then_catenary("{length: " + std::to_string(piece_length) +
                                       ", end_bending_stiffness: " + std::to_string(end_ei) + "}");
    y.replace(y.find("bending_stiffness: 2.8e5"), 24, "bending_stiffness: " + std::to_string(1.02 * least_uniform));
    return test_scenes::refusal_of_yaml(y);
  };
  auto least_named = [&](double piece_length) {
    const std::string m = stiff_enough_only(piece_length, 1.0);
    const std::size_t at = m.find("at least ");
    EXPECT_NE(m.find(f + ".end_bending_stiffness"), std::string::npos) << m;
    return at == std::string::npos ? 0.0 : std::stod(m.substr(at + 9));
  };
  const double whole = least_named(10.0), half = least_named(5.0);
  EXPECT_GT(whole, 0.0);
  EXPECT_LT(whole, least_uniform);
  EXPECT_LT(half, whole);
  for (const double piece_length : {10.0, 5.0}) {
    const double least = piece_length == 10.0 ? whole : half;
    EXPECT_EQ(stiff_enough_only(piece_length, 1.01 * least), "") << piece_length;
    EXPECT_NE(stiff_enough_only(piece_length, 0.99 * least).find(f + ".end_bending_stiffness"), std::string::npos) << piece_length;
  }
  refused(rail_then_catenary("{length: 5.0, end_bending_stiffness: 7e4, shape: linear}"), f + ".shape");
  // A rail no catenary joins has no end for a piece.
  std::string alone = rail_yaml(3, 5e6, 0.25);
  alone.insert(alone.find("  support_stiffness:"), "  transition_piece: {length: 5.0, end_bending_stiffness: 7e4}\n");
  refused(alone, "conductor_rail.transition_piece");
}
