// An external (hardware-in-the-loop) pantograph: the catenary driven by a measured force. Fed the
// contact force that a simulated lumped pantograph produces, the wires must move exactly as in
// the fully simulated pass (same distributed contact, same time steps): this is the loop a rig
// closes, without the rig.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <sstream>

#include "catenary_sim/core/simulation.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

namespace {

Scene reference(bool external) {
  return test_scenes::edited_scene("reference_55m.yaml", [external](YAML::Node& root) {
    root["numerics"]["dt"] = 0.0008;  // the same fixed step for both (auto dt sees the pantograph)
    if (external) {
      YAML::Node p = root["pantographs"][0];
      p["type"] = "external";
      p.remove("masses");
      p.remove("stiffness");
      p.remove("damping");
    }
  });
}

}  // namespace

TEST(ExternalPantograph, MeasuredForceDrivesTheCatenaryExactlyLikeTheSimulatedPantograph) {
  Simulation simulated(reference(false)), driven(reference(true));
  const Model& ms = simulated.model();
  const Model& md = driven.model();
  ASSERT_TRUE(md.pantographs[0].external);
  ASSERT_EQ(md.n_catenary_dof, ms.n_catenary_dof);
  ASSERT_EQ(md.dt, ms.dt);
  std::string err;
  // The rig's first reading: the static contact force of the simulated pantograph (eq. 23).
  ASSERT_TRUE(driven.set_external_force(0, total_contact_force(ms, simulated.state(), 0), &err)) << err;
  Simulation fresh(reference(true));  // eq. 23 of the driven line uses the same force
  double max_diff = 0.0;
  for (int n = 0; n < 3000; ++n) {
    // The force the simulated pantograph applies in this step is its observation at t_n.
    ASSERT_TRUE(driven.set_external_force(0, total_contact_force(ms, simulated.state(), 0), &err)) << err;
    ASSERT_EQ(simulated.step(), StepStatus::kOk);
    ASSERT_EQ(driven.step(), StepStatus::kOk);
    for (int i = 0; i < ms.n_catenary_dof; ++i)
      max_diff = std::max(max_diff, std::fabs(simulated.state().u[i] - driven.state().u[i]));
  }
  // Both apply k0-penalty forces with the same weights at the same times; only the initial static
  // state differs by how eq. 23 is solved (a spring-coupled head against a given force): the
  // difference is round-off of the static solve, far below a micrometre.
  EXPECT_LT(max_diff, 1e-9);
}

TEST(ExternalPantograph, ContactPointMotionIsTheWireUnderTheCollector) {
  Simulation sim(reference(true));
  const Model& m = sim.model();
  std::vector<ContactPointMotion> c0, c1;
  for (int n = 0; n < 1000; ++n) sim.step();
  contact_point_motion(m, sim.state(), 0, c0);
  const double t0 = sim.state().time;
  sim.step();
  contact_point_motion(m, sim.state(), 0, c1);
  ASSERT_EQ(c0.size(), 1u);
  ASSERT_TRUE(c0[0].on_wire);
  EXPECT_NEAR(c1[0].height, sim.state().wire_height_under(m, 0, 0), 1e-12);  // the eq. 12 height
  // The height the moving pantograph meets changes at path_velocity: the mean of the values at
  // both ends of a step matches the difference quotient of the heights. The velocity at the
  // state's time is the half-step velocity advanced by half a step with the previous step's
  // acceleration, so each end is uncertain by dt/2 times the change of acceleration over a step
  // (the contact point carries the stiff penalty spring, whose accelerations vary fast).
  const double dt = sim.state().time - t0;
  const double fd = (c1[0].height - c0[0].height) / dt;
  const double tol = 0.5 * dt * (std::fabs(c0[0].acceleration) + std::fabs(c1[0].acceleration)) + 1e-4;
  EXPECT_NEAR(0.5 * (c0[0].path_velocity + c1[0].path_velocity), fd, tol);
  // Without the train's motion along the slope, the wire's own velocity would not match.
  EXPECT_GT(std::fabs(0.5 * (c0[0].velocity + c1[0].velocity) - fd), tol);
}

TEST(ExternalPantograph, BadMeasurementsAreRejectedAndLeaveTheStateUnchanged) {
  Simulation sim(reference(true));
  std::string err;
  const double before = sim.state().external_force[0];
  for (double bad : {std::nan(""), double(INFINITY), -100.0, 5000.0}) {
    EXPECT_FALSE(sim.set_external_force(0, bad, &err));
    EXPECT_NE(err.find("rejected: allowed -50 to 2000 N"), std::string::npos) << err;
    EXPECT_EQ(sim.state().external_force[0], before);
  }
  EXPECT_TRUE(sim.set_external_force(0, -3.0, &err));  // load-cell noise without contact
  EXPECT_EQ(sim.state().external_force[0], 0.0);
  Simulation lumped(reference(false));
  EXPECT_FALSE(lumped.set_external_force(0, 100.0, &err));
  EXPECT_NE(err.find("not an external"), std::string::npos) << err;
}
