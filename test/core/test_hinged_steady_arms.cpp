// Hinged steady arms (docs/hinged_steady_arms.md): eq. 4's k_A and the tip mass from the arm as
// built. The arm's stiffness against its exact statics, the wire's lateral stiffness it works
// against, the arm as the spring of that stiffness and mass, and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "catenary_sim/core/model/build_model.hpp"
#include "catenary_sim/core/model/lateral.hpp"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/scene/scene.hpp"
#include "catenary_sim/core/simulation.hpp"
#include "../support/scene_refusal.hpp"
#include "../support/scenes.hpp"

namespace cs = catenary_sim;

namespace {

const char* const kHinged = "reference_55m_hinged_arms.yaml";

// The largest contact-wire uplift at any steady arm over a pass, and the contact force at every
// step.
struct Pass {
  double max_arm_uplift = 0.0;
  std::vector<double> force;
};

Pass run(const cs::Scene& scene) {
  cs::Simulation sim(scene);
  const cs::Model& m = sim.model();
  Pass p;
  while (!sim.finished()) {
    EXPECT_EQ(sim.step(), cs::StepStatus::kOk) << sim.status_message();
    p.force.push_back(sim.state().pantograph_force_on(m, 0, 0));
    for (const cs::SupportSpring& sp : m.springs)
      if (sp.steady_arm) p.max_arm_uplift = std::max(p.max_arm_uplift, sim.state().u[sp.dof]);
  }
  return p;
}

// The reference line on `spans` spans, its steady arms replaced by `arms`.
cs::Scene line_with_arms(const YAML::Node& arms, int spans) {
  return test_scenes::edited_scene(kHinged, [&](YAML::Node& root) {
    root["line"]["span_count"] = spans;
    root["steady_arms"] = arms;
  });
}

}  // namespace

// The arm's vertical stiffness from its exact statics, by another route than the model's closed
// form. A bar of length a hinged at the registration tube, a load W down at its end with the
// clamp's weight, its own weight at mid-length; the wire pulls the end outward with F_h less k_w
// times the end's outward travel a (cos(theta) - cos(theta0)). Its moments about the hinge:
// F(theta) sin(theta) = (W + m_c g + m_a g / 2) cos(theta), solved by Newton for W +- 0.01 N, the
// end at z = -a sin(theta). The central difference of W against z is the stiffness to
// (0.01 / W)^2 ~ 1e-9; 1e-7 leaves room for the round-off of z's difference (1e-16 a / (0.02 N /
// k) ~ 1e-11). W is the wire's load on the clamp: the support's static reaction less the tip
// mass's weight and the weightless share of its inertia, which the reaction carries alike. k_w
// is the model's (checked on its own below).
TEST(HingedSteadyArms, StiffnessIsTheArmsExactStaticsLinearised) {
  const cs::Scene scene = cs::load_scene_file(test_scenes::scene_path(kHinged));
  const cs::HingedArmSpec arm = *scene.steady_arms->hinged_arm;
  const cs::Model m = cs::build_model(scene);
  const double g = scene.gravity, a = arm.length;
  const double weights = arm.clamp_mass * g + 0.5 * arm.linear_mass * a * g;
  int arms = 0;
  for (const cs::SupportSpring& sp : m.springs) {
    if (!sp.steady_arm) continue;
    ++arms;
    ASSERT_TRUE(sp.hinged_arm());
    // The arm's inertia at its end, which moves at z' / cos(theta0): the tip mass / cos^2.
    EXPECT_NEAR(sp.arm_tip_mass * std::pow(std::cos(sp.arm_inclination), 2), arm.tip_mass(), 1e-12);
    // f0 carries the wire's load, the tip mass's weight and the inertia's weightless share.
    const double W = sp.static_force - sp.arm_tip_mass * g, kw = sp.arm_wire_lateral_stiffness;
    auto solve = [&](double load, double cos0) {  // theta of the moments' balance, Newton from 0.3
      double th = 0.3;
      for (int it = 0; it < 50; ++it) {
        const double F = *arm.pull_off - kw * a * (std::cos(th) - cos0);
        const double r = F * std::sin(th) - (load + weights) * std::cos(th);
        const double dr = kw * a * std::sin(th) * std::sin(th) + F * std::cos(th) + (load + weights) * std::sin(th);
        th -= r / dr;
      }
      return th;
    };
    // The assembly: F = F_h there, so theta0 is the arm's without the wire's give.
    const double theta0 = std::atan((W + weights) / *arm.pull_off);
    EXPECT_NEAR(solve(W, std::cos(theta0)), theta0, 1e-14);
    const double dW = 0.01;
    const double zp = -a * std::sin(solve(W + dW, std::cos(theta0))), zm = -a * std::sin(solve(W - dW, std::cos(theta0)));
    const double k = 2.0 * dW / (zm - zp);
    EXPECT_NEAR(sp.stiffness, k, 1e-7 * k) << "arm at " << sp.x << " m";
    EXPECT_NEAR(sp.arm_inclination, theta0, 1e-12) << "arm at " << sp.x << " m";
    // The arm hangs below its hinge on this line: the wire pulls its registration down.
    EXPECT_GT(sp.arm_inclination, 0.0);
  }
  EXPECT_EQ(arms, 9);  // the intermediate supports of 10 spans
}

// The wire's lateral stiffness that the arm's sideways travel works against: on a lone contact
// wire without bending stiffness (a string) held at its other supports it is T / L1 + T / L2 for
// the spans L1, L2 beside the arm. The C1 beam elements round the string's kink at the arm over
// an element, an error first order in the element length h (0.09 % at 0.25 m): it halves with
// h (ratio 0.45-0.55), and the extrapolation 2 k(h / 2) - k(h) meets the string to 1e-5 (its
// second-order rest). With droppers the pendulums add to it.
TEST(HingedSteadyArms, TheWiresLateralStiffnessIsTheStringsAtTheRegistration) {
  const double T = 20000.0;
  auto stiffness = [&](double h) {
    std::ostringstream y;
    y << "name: string\nline: {spans: [50.0, 40.0, 60.0], encumbrance: 1.2}\n"
      << "contact_wire: {linear_mass: 1.35, tension: " << T << "}\n"
      << "steady_arms: {length: 1.15, linear_mass: 0.78, pull_off: 1500}\n"
      << "numerics: {element_length: " << h << "}\n";
    const cs::Model m = cs::build_model(cs::load_scene_string(y.str()));
    std::vector<double> k;
    for (const cs::SupportSpring& sp : m.springs) k.push_back(sp.arm_wire_lateral_stiffness);
    return k;
  };
  const std::vector<double> expected{T / 50.0 + T / 40.0, T / 40.0 + T / 60.0};
  const std::vector<double> coarse = stiffness(0.25), fine = stiffness(0.125);
  ASSERT_EQ(coarse.size(), 2u);
  ASSERT_EQ(fine.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    const double ratio = (fine[k] - expected[k]) / (coarse[k] - expected[k]);
    EXPECT_GT(ratio, 0.45) << "arm " << k;
    EXPECT_LT(ratio, 0.55) << "arm " << k;
    EXPECT_NEAR(2.0 * fine[k] - coarse[k], expected[k], 1e-5 * expected[k]) << "arm " << k;
  }
  const cs::Model line = cs::build_model(cs::load_scene_file(test_scenes::scene_path(kHinged)));
  for (const cs::SupportSpring& sp : line.springs) {
    if (sp.steady_arm) {
      EXPECT_GT(sp.arm_wire_lateral_stiffness, 2.0 * 22000.0 / 55.0);
    }
  }
}

// The limit that is today's model: a hinged arm is eq. 4's spring of its k_A with its inertia on
// the wire's node, so a line whose springs are given those values runs the same pass. On three
// equal spans the two arms mirror each other, so one spring stands for both: their k_A agree to
// round-off (1e-12), and the forces to far below 1e-6 N, where a wrong mass or stiffness moves
// the contact force by newtons.
TEST(HingedSteadyArms, IsTheSpringOfItsStiffnessAndTipMass) {
  YAML::Node hinged = YAML::LoadFile(test_scenes::scene_path(kHinged))["steady_arms"];
  const cs::Scene with_arms = line_with_arms(hinged, 3);
  const cs::Model m = cs::build_model(with_arms);
  std::vector<double> k;
  for (const cs::SupportSpring& sp : m.springs)
    if (sp.steady_arm) k.push_back(sp.stiffness);
  ASSERT_EQ(k.size(), 2u);
  EXPECT_NEAR(k[0], k[1], 1e-12 * k[0]);
  YAML::Node spring;
  std::ostringstream ks;
  ks.precision(17);
  ks << k[0];
  spring["stiffness"] = ks.str();
  double tip = 0.0;
  for (const cs::SupportSpring& sp : m.springs)
    if (sp.steady_arm) tip = sp.arm_tip_mass;
  std::ostringstream ms;
  ms.precision(17);
  ms << tip;
  spring["mass"] = ms.str();
  const Pass a = run(with_arms), b = run(line_with_arms(spring, 3));
  ASSERT_EQ(a.force.size(), b.force.size());
  for (std::size_t i = 0; i < a.force.size(); ++i) ASSERT_NEAR(a.force[i], b.force[i], 1e-6) << "step " << i;
  EXPECT_GT(a.max_arm_uplift, 0.0);
}

// On a 3-D line each arm's pull-off comes from the lateral statics of the stagger and the curves.
// A zigzag of +-s on straight track, the messenger above the contact wire (no dropper leans),
// pulls each arm with 4 T (s - F / k) / L, the registrations giving F / k toward the track centre
// on their lateral springs k: F = (4 T s / L) / (1 + 4 T / (L k)). A curve of radius R without
// stagger pulls with T L / R toward the curve's centre (every support gives alike). The beam
// elements round the wire's kink at the support (0.1 % at 0.25 m, as above) and its bending
// stiffness spreads it over sqrt(EI / T) = 0.09 m: 0.5 %. The lateral plane the pass then builds
// reports the same pull-off at the same support (one statics: 1e-9).
TEST(HingedSteadyArms, OnA3dLineThePullOffIsTheStaggersAndTheCurves) {
  auto line = [](const std::function<void(YAML::Node&)>& edit) {
    return cs::build_model(test_scenes::edited_scene("reference_55m_3d_hinged_arms.yaml", [&](YAML::Node& root) {
      root["line"]["span_count"] = 6;
      root.remove("wind");
      root["stagger"].remove("messenger");
      edit(root);
    }));
  };
  auto check = [](const cs::Model& m, double expected, double side) {
    ASSERT_TRUE(m.lateral);
    int arms = 0;
    for (const cs::SupportSpring& sp : m.springs) {
      if (!sp.steady_arm) continue;
      ++arms;
      EXPECT_NEAR(sp.arm_pull_off, expected, 0.005 * expected) << "arm at " << sp.x << " m";
      if (side != 0.0) {
        EXPECT_EQ(sp.arm_pull_side, side) << "arm at " << sp.x << " m";
      }
      for (const cs::LateralSupport& ls : m.lateral->supports) {
        if (m.wires[ls.wire].is_contact_wire && std::abs(ls.x - sp.x) < 1e-9) {
          EXPECT_NEAR(std::abs(ls.pull_off), sp.arm_pull_off, 1e-9 * expected);
        }
      }
    }
    EXPECT_EQ(arms, 5);
  };
  const double T = 22000.0, L = 55.0, k = 2.0e5;  // reference_55m_3d.yaml's steady_arm_stiffness
  const cs::Model zigzag = line([](YAML::Node&) {});
  check(zigzag, 4.0 * T * 0.3 / L / (1.0 + 4.0 * T / (L * k)), 0.0);
  // The wire's give that the arm drags against is the 2-D line's: the lateral springs at the
  // registrations are the arms themselves, stiff along their length, not the wire (round-off).
  const cs::Model flat = cs::build_model(line_with_arms(YAML::LoadFile(test_scenes::scene_path(kHinged))["steady_arms"], 6));
  std::vector<double> kw3, kw2;
  for (const cs::SupportSpring& sp : zigzag.springs)
    if (sp.steady_arm) kw3.push_back(sp.arm_wire_lateral_stiffness);
  for (const cs::SupportSpring& sp : flat.springs)
    if (sp.steady_arm) kw2.push_back(sp.arm_wire_lateral_stiffness);
  ASSERT_EQ(kw3.size(), kw2.size());
  for (std::size_t i = 0; i < kw2.size(); ++i) EXPECT_NEAR(kw3[i], kw2[i], 1e-9 * kw2[i]) << "arm " << i;
  const cs::Model curve = line([](YAML::Node& root) {
    root["stagger"]["contact_wire"] = std::vector<double>{0.0};
    root["alignment"]["radius"] = 1000.0;
  });
  check(curve, T * L / 1000.0, 1.0);
}

namespace {

// reference_55m_3d_hinged_arms.yaml on 6 spans without wind (nothing else moves a registration
// sideways), at the balanced preset; `edit` after.
cs::Scene three_d_line_with_arms(const std::function<void(YAML::Node&)>& edit) {
  return test_scenes::edited_scene("reference_55m_3d_hinged_arms.yaml", [&](YAML::Node& root) {
    root["line"]["span_count"] = 6;
    root["numerics"]["preset"] = "balanced";
    root.remove("wind");
    edit(root);
  });
}

// The arm's end's outward travel with its end raised by u, from the arm's geometry alone:
// side a (cos(theta) - cos(theta0)), sin(theta) = sin(theta0) - u / a.
double arm_end_travel(const cs::SupportSpring& sp, double u) {
  const double theta = std::asin(std::sin(sp.arm_inclination) - u / sp.arm_length);
  return sp.arm_pull_side * sp.arm_length * (std::cos(theta) - std::cos(sp.arm_inclination));
}

// The registrations of a 3-D line's hinged arms: per intermediate contact-wire support with a
// hinged arm, its SupportSpring and lateral DOF.
struct Registration {
  const cs::SupportSpring* arm = nullptr;
  int lateral = 0;
};
std::vector<Registration> registrations(const cs::Model& m) {
  std::vector<Registration> out;
  for (const cs::LateralSupport& ls : m.lateral->supports) {
    const cs::Wire& w = m.wires[ls.wire];
    if (!w.is_contact_wire || ls.anchor) continue;
    for (const cs::SupportSpring& sp : m.springs)
      if (sp.hinged_arm() && sp.dof == w.w_dof + ls.node) out.push_back({&sp, m.lateral->wires[ls.wire].w_dof + ls.node});
  }
  return out;
}

}  // namespace

// On a 3-D line the lateral plane moves each registration point with its arm's end: the held
// node (no stagger.steady_arm_stiffness) to y0 + side a (cos(theta(u)) - cos(theta0)), u the
// registration's uplift, at the end of every step of a pass at 300 km/h, to round-off of the
// y0 + travel sum (1e-12 m, a billionth of the travel). The anchors (section ends) and the
// messenger's supports do not move at all. With either damping step (the centred one moves a held
// node through its row of the wires' solve).
class HingedArmDamping : public ::testing::TestWithParam<const char*> {};

TEST_P(HingedArmDamping, OnA3dLineTheRegistrationPointFollowsTheArmsEnd) {
  cs::Simulation sim(three_d_line_with_arms([](YAML::Node& root) {
    root["stagger"].remove("steady_arm_stiffness");
    root["numerics"]["damping"] = GetParam();
  }));
  const cs::Model& m = sim.model();
  ASSERT_TRUE(m.lateral);
  const std::vector<Registration> regs = registrations(m);
  ASSERT_EQ(regs.size(), 5u);
  const cs::State& s = sim.state();
  double worst = 0.0, largest = 0.0;
  int steps = 0;
  while (!sim.finished()) {
    ASSERT_EQ(sim.step(), cs::StepStatus::kOk) << sim.status_message();
    ++steps;
    for (std::size_t k = 0; k < regs.size(); ++k) {
      const cs::SupportSpring& sp = *regs[k].arm;
      const double y = s.lateral.y[regs[k].lateral] - m.lateral->initial[regs[k].lateral];
      ASSERT_NEAR(y, arm_end_travel(sp, s.u[sp.dof]), 1e-12) << "arm at " << sp.x << " m, step " << steps;
      worst = std::max(worst, std::fabs(y - arm_end_travel(sp, s.u[sp.dof])));
      largest = std::max(largest, std::fabs(y));
    }
    // Every other held node (the anchors, the messenger's rigid supports) stays where it was built.
    for (int i = 0; i < m.lateral->n; ++i) {
      if (m.lateral->inv_mass[i] > 0.0) continue;
      bool registration = false;
      for (const Registration& r : regs) registration |= r.lateral == i;
      if (!registration) {
        ASSERT_EQ(s.lateral.y[i], m.lateral->initial[i]) << "held node " << i << ", step " << steps;
      }
    }
  }
  // The pantograph lifts each arm by some 25 mm (docs/hinged_steady_arms.md): tan(24 degrees) of it.
  EXPECT_GT(largest, 5e-3);
  std::printf("%d steps: largest registration travel %.2f mm, off its arm's end by %.1e m at most\n", steps, 1e3 * largest, worst);
}

INSTANTIATE_TEST_SUITE_P(Damping, HingedArmDamping, ::testing::Values("half_step", "centred"));

namespace {

// The largest uplift (m) of each steady arm over a pass, in line order.
std::vector<double> largest_arm_uplifts(cs::Simulation& sim) {
  const cs::Model& m = sim.model();
  std::vector<const cs::SupportSpring*> arms;
  for (const cs::SupportSpring& sp : m.springs)
    if (sp.steady_arm) arms.push_back(&sp);
  std::sort(arms.begin(), arms.end(), [](const cs::SupportSpring* a, const cs::SupportSpring* b) { return a->x < b->x; });
  std::vector<double> largest(arms.size(), 0.0);
  while (!sim.finished()) {
    EXPECT_EQ(sim.step(), cs::StepStatus::kOk) << sim.status_message();
    if (sim.state().status != cs::StepStatus::kOk) break;
    for (std::size_t k = 0; k < arms.size(); ++k) largest[k] = std::max(largest[k], sim.state().u[arms[k]->dof]);
  }
  return largest;
}

}  // namespace

// Both ways, quasi-statically: a 3-D line whose messenger runs straight above the contact wire
// (the droppers hang plumb, so nothing but the registrations joins the planes), its arms held
// across the track, against its 2-D twin, the same arms with the same pull-off, whose k_A holds
// the wire's answer to the arm's travel as the static k_w tan^2 theta0. On the 3-D line that
// share is left out of k_A: the lateral plane moves the registration point and its reaction comes
// back through the arm. At 10 km/h a support's uplift rises over some 10 s, against the lateral
// spans' first mode of 1.2 Hz, so the wire answers with its static stiffness and the two lines
// lift each arm alike. 1.5 %: what is left is the two lines' own slow vertical motion, which
// differs with the lateral plane's (0.6 % at most here, 1.6 % at 20 km/h); the reaction itself is
// some 5 % of the uplift (the 3-D line without it lifts the arms 4-6 % more), and a reaction with
// the wrong sign throws the arms off (they rise by decimetres).
TEST(HingedSteadyArms, OnA3dLineTheArmsTravelGivesTheStaticStiffnessQuasiStatically) {
  const cs::Scene three_d = three_d_line_with_arms([](YAML::Node& root) {
    root["train"]["speed_kmh"] = 10.0;
    root["stagger"].remove("messenger");
    root["stagger"].remove("steady_arm_stiffness");
  });
  cs::Simulation sim_3d(three_d);
  const cs::Model& m3 = sim_3d.model();
  ASSERT_TRUE(m3.lateral);
  const std::vector<Registration> regs = registrations(m3);
  ASSERT_EQ(regs.size(), 5u);
  const double pull_off = regs[2].arm->arm_pull_off;
  cs::Simulation sim_2d(three_d_line_with_arms([&](YAML::Node& root) {
    root["train"]["speed_kmh"] = 10.0;
    root.remove("stagger");
    root["steady_arms"]["pull_off"] = pull_off;
  }));
  ASSERT_FALSE(sim_2d.model().lateral);
  std::vector<double> k_2d;
  for (const cs::SupportSpring& sp : sim_2d.model().springs)
    if (sp.steady_arm) k_2d.push_back(sp.stiffness);
  // The same arms: k_A with the lateral plane's share added back is the 2-D line's (away from the
  // section's ends, where the arms beside the anchors are pulled 0.1 % more).
  for (std::size_t k = 1; k + 1 < regs.size(); ++k) {
    const Registration& r = regs[k];
    EXPECT_NEAR(r.arm->arm_pull_off, pull_off, 1e-5 * pull_off) << "arm at " << r.arm->x << " m";
    EXPECT_NEAR(r.arm->static_stiffness(), k_2d[2], 1e-5 * k_2d[2]) << "arm at " << r.arm->x << " m";
    EXPECT_GT(r.arm->arm_lateral_share, 0.2 * r.arm->static_stiffness());
  }
  const std::vector<double> up_3d = largest_arm_uplifts(sim_3d), up_2d = largest_arm_uplifts(sim_2d);
  ASSERT_EQ(up_3d.size(), up_2d.size());
  for (std::size_t k = 1; k + 1 < up_3d.size(); ++k) {  // (the arms beside the section's ends)
    std::printf("arm %zu: largest uplift %.3f mm on the 3-D line, %.3f mm on the 2-D one\n", k, 1e3 * up_3d[k], 1e3 * up_2d[k]);
    EXPECT_GT(up_2d[k], 0.01);
    EXPECT_NEAR(up_3d[k], up_2d[k], 0.015 * up_2d[k]) << "arm " << k;
  }
}

// A pass that starts with the pantograph under an arm (the initial state's statics lift it by
// some 18 mm): the lateral plane starts in its statics with the registration moved out with the
// arm (held: to its arm's end; on its stiff spring: 99 % of the way), so the wire's answer on the
// arm is the static one, near the share of k_A that statics took, -k_w tan^2 theta0 u. 10 %: k_w
// holds every other support, where the statics lets the neighbouring arms' registrations move out
// too (their arms lifted a few mm), each changing the wire's pull at this one (5 % measured). The
// first step then changes it by less than 1 %: at rest the wire has no waves to answer with. A
// lateral plane left in its calm state would answer the moved registration with the wire's local
// stiffness, hundreds of newtons.
TEST(HingedSteadyArms, APassStartingUnderAnArmStartsInTheArmsStatics) {
  for (const bool held : {true, false}) {
    cs::Simulation sim(three_d_line_with_arms([&](YAML::Node& root) {
      root["train"]["start"] = 165.0;
      if (held) root["stagger"].remove("steady_arm_stiffness");
    }));
    const char* what = held ? "held" : "on its spring";
    const cs::Model& m = sim.model();
    const std::vector<Registration> regs = registrations(m);
    std::size_t at = regs.size();
    for (std::size_t k = 0; k < regs.size(); ++k)
      if (std::fabs(regs[k].arm->x - 165.0) < 1e-9) at = k;
    ASSERT_LT(at, regs.size());
    const cs::SupportSpring& arm = *regs[at].arm;
    const double u0 = sim.state().u[arm.dof], f0 = sim.state().lateral.registration_force[at];
    const double travel = arm_end_travel(arm, u0), y = sim.state().lateral.y[regs[at].lateral] - m.lateral->initial[regs[at].lateral];
    EXPECT_GT(u0, 0.01);
    EXPECT_NEAR(y, travel, held ? 1e-12 : 0.01 * travel) << what;
    EXPECT_NEAR(f0, -arm.arm_lateral_share * u0, 0.1 * arm.arm_lateral_share * u0) << what;
    ASSERT_EQ(sim.step(), cs::StepStatus::kOk);
    const double f1 = sim.state().lateral.registration_force[at];
    std::printf("%s: u %.2f mm, the wire's answer %.3f N (static share %.3f N), %.3f N after a step\n", what, 1e3 * u0, f0,
                -arm.arm_lateral_share * u0, f1);
    EXPECT_NEAR(f1, f0, 0.01 * std::fabs(f0)) << what;
  }
}

// A slow pass (20 km/h) over reference_55m_3d.yaml's leaning droppers (the messenger above the
// track centre, the contact wire at +-0.3 m) with hinged arms held across the track: quasi-static,
// the uplift at a support is the pantograph's 100 N on the line's elasticity there (about
// 0.18 mm/N: some 20 mm), and nothing should grow after the pantograph has passed. 25 mm allows
// the leaning droppers' own share; the registrations' travel, moving the lean of the droppers
// beside each support, must not drive the arms (with the travel acting one way only, without the
// wire's reaction on the arm, the loop grows to 0.4 m here).
TEST(HingedSteadyArms, ASlowPassOverLeaningDroppersStaysBounded) {
  cs::Simulation sim(three_d_line_with_arms([](YAML::Node& root) {
    root["train"]["speed_kmh"] = 20.0;
    root["stagger"].remove("steady_arm_stiffness");
  }));
  const std::vector<double> largest = largest_arm_uplifts(sim);
  double worst = 0.0;
  for (double u : largest) worst = std::max(worst, u);
  std::printf("largest uplift at an arm %.2f mm\n", 1e3 * worst);
  EXPECT_GT(worst, 0.01);
  EXPECT_LT(worst, 0.025);
}

// Bad input: each field refused by name with what is allowed.
TEST(HingedSteadyArms, BadInputIsRefusedByName) {
  const std::string base =
      "name: x\nline: {span_length: 55.0, span_count: 4, encumbrance: 1.2}\n"
      "contact_wire: {linear_mass: 1.35, tension: 22000}\n"
      "messenger: {linear_mass: 1.08, tension: 16000}\n"
      "droppers: {positions: [4.5, 27.5, 50.5], axial_stiffness: 200000}\n";
  const std::string arm = "length: 1.15, linear_mass: 0.78";
  test_scenes::expect_refused(base + "steady_arms: {" + arm + ", pull_off: 480, stiffness: 2000}\n", "steady_arms.stiffness");
  test_scenes::expect_refused(base + "steady_arms: {" + arm + ", pull_off: 480, mass: 1}\n", "steady_arms.mass");
  test_scenes::expect_refused(base + "steady_arms: {" + arm + "}\n", "steady_arms.pull_off");
  test_scenes::expect_refused(base + "steady_arms: {" + arm + ", pull_off: 0}\n", "steady_arms.pull_off");
  test_scenes::expect_refused(base + "steady_arms: {" + arm + ", pull_off: -480}\n", "steady_arms.pull_off");
  test_scenes::expect_refused(base + "steady_arms: {length: 0, linear_mass: 0.78, pull_off: 480}\n", "steady_arms.length");
  // (An arm of 1e-310 m would make k_A infinite and the pass NaN.)
  for (const char* tiny : {"1e-310", "0.099"})
    test_scenes::expect_refused(base + "steady_arms: {length: " + tiny + ", linear_mass: 0, pull_off: 1e5}\n", "steady_arms.length");
  EXPECT_EQ(test_scenes::refusal_of_yaml(base + "steady_arms: {length: 0.1, linear_mass: 0.78, pull_off: 480}\n"), "");
  test_scenes::expect_refused(base + "steady_arms: {length: 6, linear_mass: 0.78, pull_off: 480}\n", "steady_arms.length");
  test_scenes::expect_refused(base + "steady_arms: {length: 1.15, pull_off: 480}\n", "steady_arms.linear_mass");
  test_scenes::expect_refused(base + "steady_arms: {" + arm + ", pull_off: 480, clamp_mass: -1}\n", "steady_arms.clamp_mass");
  test_scenes::expect_refused(base + "steady_arms: {" + arm + ", pull_off: 480, inclination: 0.1}\n", "steady_arms.inclination");
  test_scenes::expect_refused(base + "steady_arms: {" + arm + ", pull_off: 480}\nmessenger_supports: {length: 1.0}\n",
                              "messenger_supports.length");
  test_scenes::expect_refused(base + "steady_arms: {" + arm + ", pull_off: 480}\nstagger: {contact_wire: [0.3, -0.3]}\n",
                              "steady_arms.pull_off");
  // Too little pull-off for the load at the registration: the arm would hang near vertical, its
  // k_A without bound. Refused when the design statics know the load, naming the field.
  auto refused_at_build = [](const std::string& yaml, const std::string& field) {
    const cs::Scene scene = cs::load_scene_string(yaml);
    try {
      cs::build_model(scene);
      ADD_FAILURE() << "accepted; expected a refusal naming " << field;
    } catch (const cs::SceneError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(field), std::string::npos) << what;
      EXPECT_NE(what.find("at least"), std::string::npos) << what;
    }
  };
  refused_at_build(base + "steady_arms: {" + arm + ", pull_off: 20}\n", "steady_arms.pull_off");
  // On a 3-D line without stagger or curve nothing pulls the arms: the stagger is named.
  refused_at_build(base + "steady_arms: {" + arm + "}\nstagger: {contact_wire: [0.0]}\n", "stagger.contact_wire");
}
