// Hinged steady arms (docs/hinged_steady_arms.md): eq. 4's k_A and the tip mass from the arm as
// built. The arm's stiffness against its exact statics, the arm as the spring of that stiffness
// and mass, what the pull-off does to the uplift at the supports, and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "catenary_sim/core/model/build_model.hpp"
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

// The reference line on 6 spans (enough for two spans in the analysis section), its steady arms
// replaced by `arms`.
cs::Scene line_with_arms(const YAML::Node& arms) {
  return test_scenes::edited_scene(kHinged, [&](YAML::Node& root) {
    root["line"]["span_count"] = 6;
    root["steady_arms"] = arms;
  });
}

}  // namespace

// The arm's vertical stiffness from its exact statics, by another route than the model's closed
// form. A bar of length a hinged at the registration tube, pulled along itself by F_h, a load W
// down at its tip with the clamp's weight, its own weight at mid-length: its moments about the
// hinge give tan(theta) = (W + m_c g + m_a g / 2) / F_h, the tip at z = -a sin(theta). A central
// difference of W against z over +-0.01 N is the stiffness to (0.01 / W)^2 ~ 1e-9; 1e-7 leaves
// room for the round-off of z's difference (1e-16 * a / (0.02 N / k) ~ 1e-11). W is the wire's
// load on the clamp: the support's static reaction less the weight of the tip mass it carries.
TEST(HingedSteadyArms, StiffnessIsTheArmsExactStaticsLinearised) {
  const cs::Scene scene = cs::load_scene_file(test_scenes::scene_path(kHinged));
  const cs::HingedArmSpec arm = *scene.steady_arms->hinged_arm;
  const cs::Model m = cs::build_model(scene);
  const double g = scene.gravity;
  auto tip_height = [&](double W) {
    return -arm.length * std::sin(std::atan((W + arm.clamp_mass * g + 0.5 * arm.linear_mass * arm.length * g) / arm.pull_off));
  };
  int arms = 0;
  for (const cs::SupportSpring& sp : m.springs) {
    if (!sp.steady_arm) continue;
    ++arms;
    ASSERT_TRUE(sp.hinged_arm());
    const double W = sp.static_force - arm.tip_mass() * g;
    const double dW = 0.01;
    const double k = 2.0 * dW / (tip_height(W - dW) - tip_height(W + dW));
    EXPECT_NEAR(sp.stiffness, k, 1e-7 * k) << "arm at " << sp.x << " m";
    EXPECT_NEAR(std::sin(sp.arm_inclination), -tip_height(W) / arm.length, 1e-12) << "arm at " << sp.x << " m";
    // The arm hangs below its hinge on this line: the wire pulls its registration down.
    EXPECT_GT(sp.arm_inclination, 0.0);
  }
  EXPECT_EQ(arms, 9);  // the intermediate supports of 10 spans
}

// The limit that is today's model: a hinged arm is eq. 4's spring of its k_A with its tip mass on
// the wire's node, so a line whose springs are given those values runs the same pass. Every arm
// of this line carries the same load, so one spring stands for all; they agree to round-off
// (1e-12), so the forces agree to far below a newton's millionth (1e-6 N; a wrong mass or
// stiffness moves them by newtons).
TEST(HingedSteadyArms, IsTheSpringOfItsStiffnessAndTipMass) {
  YAML::Node hinged = YAML::LoadFile(test_scenes::scene_path(kHinged))["steady_arms"];
  const cs::Scene with_arms = line_with_arms(hinged);
  const cs::Model m = cs::build_model(with_arms);
  double k = 0.0;
  for (const cs::SupportSpring& sp : m.springs)
    if (sp.steady_arm) {
      if (k == 0.0) k = sp.stiffness;
      EXPECT_NEAR(sp.stiffness, k, 1e-12 * k);
    }
  ASSERT_GT(k, 0.0);
  YAML::Node spring;
  std::ostringstream ks;
  ks.precision(17);
  ks << k;
  spring["stiffness"] = ks.str();
  spring["mass"] = with_arms.steady_arms->hinged_arm->tip_mass();
  const Pass a = run(with_arms), b = run(line_with_arms(spring));
  ASSERT_EQ(a.force.size(), b.force.size());
  for (std::size_t i = 0; i < a.force.size(); ++i) ASSERT_NEAR(a.force[i], b.force[i], 1e-6) << "step " << i;
}

// What the arm's pull-off does: it is all that holds the arm's tip up against the pantograph, so
// a larger pull-off (more stagger, a curve) stiffens the registration and the contact wire rises
// less at the supports in the same pass; in the limit of a straight arm it is the rigid support.
TEST(HingedSteadyArms, MorePullOffLessUpliftAtTheSupports) {
  YAML::Node arms = YAML::LoadFile(test_scenes::scene_path(kHinged))["steady_arms"];
  std::vector<double> uplift;
  for (double pull_off : {300.0, 600.0, 1200.0}) {
    arms["pull_off"] = pull_off;
    uplift.push_back(run(line_with_arms(arms)).max_arm_uplift);
  }
  EXPECT_GT(uplift[0], uplift[1]);
  EXPECT_GT(uplift[1], uplift[2]);
  EXPECT_GT(uplift[2], 0.0);
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
  test_scenes::expect_refused(base + "steady_arms: {length: 6, linear_mass: 0.78, pull_off: 480}\n", "steady_arms.length");
  test_scenes::expect_refused(base + "steady_arms: {length: 1.15, pull_off: 480}\n", "steady_arms.linear_mass");
  test_scenes::expect_refused(base + "steady_arms: {" + arm + ", pull_off: 480, clamp_mass: -1}\n", "steady_arms.clamp_mass");
  test_scenes::expect_refused(base + "steady_arms: {" + arm + ", pull_off: 480, inclination: 0.1}\n", "steady_arms.inclination");
  test_scenes::expect_refused(base + "steady_arms: {" + arm + ", pull_off: 480}\nmessenger_supports: {length: 1.0}\n",
                              "messenger_supports.length");
  test_scenes::expect_refused(base + "steady_arms: {" + arm + ", pull_off: 480}\nstagger: {contact_wire: [0.3, -0.3]}\n",
                              "steady_arms.length");
  // Too little pull-off for the load at the registration: the arm would hang near vertical, its
  // k_A without bound. Refused when the design statics know the load, naming the field.
  const cs::Scene slack = cs::load_scene_string(base + "steady_arms: {" + arm + ", pull_off: 20}\n");
  try {
    cs::build_model(slack);
    ADD_FAILURE() << "a pull-off of 20 N was accepted";
  } catch (const cs::SceneError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("steady_arms.pull_off"), std::string::npos) << what;
    EXPECT_NE(what.find("at least"), std::string::npos) << what;
  }
}
