// Numerical stability at the extremes: train speeds from 0 to 0.95 c, contact stiffness from
// 1e3 to 1e7 N/m, element lengths from 0.05 to 2 m, uplift from 0 to 400 N, sudden speed and
// uplift steps. Nothing may go NaN; what is physically extreme is warned about or refused.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/model/stability.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

namespace {

const std::string& kScene = test_scenes::kReference;

// Steps up to `max_steps` (or to the end of the pass) and checks every state stays finite.
int run_finite(Simulation& sim, int max_steps) {
  int n = 0;
  for (; n < max_steps; ++n) {
    const StepStatus st = sim.step();
    if (st == StepStatus::kFinished) break;
    EXPECT_EQ(st, StepStatus::kOk) << sim.status_message();
    if (st != StepStatus::kOk) break;
  }
  EXPECT_TRUE(sim.state().u.allFinite());
  EXPECT_TRUE(sim.state().v.allFinite());
  for (double f : sim.state().contact_force) EXPECT_TRUE(std::isfinite(f) && f >= 0.0);
  return n;
}

}  // namespace

TEST(Extremes, TrainAtRestAndCreeping) {
  // At 0 km/h the pantograph stays on its static state (eq. 23): the force stays the uplift.
  Simulation rest(load_scene_file(kScene, {"train.speed_kmh=0", "train.start=302.5"}));
  run_finite(rest, 3000);
  EXPECT_NEAR(total_contact_force(rest.model(), rest.state(), 0), 100.0, 0.5);  // damped residual only
  EXPECT_FALSE(rest.finished());
  Simulation creep(load_scene_file(kScene, {"train.speed_kmh=1"}));
  run_finite(creep, 3000);
  EXPECT_TRUE(creep.model().warnings.empty());
}

TEST(Extremes, NearTheWaveSpeedWarnsAndStaysFinite) {
  const double c_kmh = std::sqrt(22000.0 / 1.35) * 3.6;  // 460 km/h
  Simulation fast(load_scene_file(kScene, {"train.speed_kmh=" + std::to_string(0.95 * c_kmh)}));
  ASSERT_EQ(fast.model().warnings.size(), 1u);
  EXPECT_NE(fast.model().warnings[0].find("above 0.7 c"), std::string::npos) << fast.model().warnings[0];
  run_finite(fast, 1000000);
  EXPECT_TRUE(fast.finished());
  Simulation below(load_scene_file(kScene, {"train.speed_kmh=" + std::to_string(0.65 * c_kmh)}));
  EXPECT_TRUE(below.model().warnings.empty());
}

TEST(Extremes, ContactStiffnessFrom1e3To1e7) {
  // The explicit limit must follow the contact: k0 = 1e7 N/m on a 0.5 kg wire node is a
  // 4500 rad/s mode (dt < 0.45 ms), stiffer than the wire's highest (about 1800 rad/s).
  const double dt_soft = build_model(load_scene_file(kScene, {"contact.stiffness=5e4"})).dt;
  const double dt_stiff = build_model(load_scene_file(kScene, {"contact.stiffness=1e7"})).dt;
  EXPECT_LT(dt_stiff, 0.5 * dt_soft);
  EXPECT_LT(dt_stiff, 2.0 / std::sqrt(1e7 / 0.5));
  for (double k : {1e3, 1e4, 1e5, 1e6, 1e7}) {
    Simulation sim(load_scene_file(kScene, {"contact.stiffness=" + std::to_string(k)}));
    SCOPED_TRACE("k0 = " + std::to_string(k) + ", dt = " + std::to_string(sim.model().dt));
    run_finite(sim, 4000);
  }
  // The implicit integrator takes the contact implicitly: 1e7 N/m at 1 ms.
  Simulation implicit(load_scene_file(kScene, {"contact.stiffness=1e7", "numerics.integrator=implicit", "numerics.dt=0.001"}));
  run_finite(implicit, 2000);
}

// The centred step leaves the springs' damping beta k explicit, and a link between two light
// masses (a bridle's or a stitch wire's clamp, a dropper, a hanger) moves them against each other
// at sqrt(k (1/m_a + 1/m_b)), above either mass's sqrt(k / m): with damping.beta at its bound the
// estimate's dt must hold there too (a bridled trolley wire with it at one mass diverged within
// 100 steps, its bridle's clamp the first to run away; on a 3-D line, across the track too).
TEST(Extremes, StiffnessDampingAtItsBoundOnTheCentredStep) {
  for (const char* scene : {"trolley_wire_bridle.yaml", "trolley_wire_bridle_3d.yaml", "reference_55m_stitched.yaml",
                            "compound_catenary.yaml"}) {
    Simulation sim(load_scene_file(test_scenes::scene_path(scene),
                                   {"damping.beta=0.1", "numerics.damping=centred", "numerics.preset=accurate"}));
    SCOPED_TRACE(std::string(scene) + ", dt = " + std::to_string(sim.model().dt));
    run_finite(sim, 3000);
  }
}

// The wind's drag on the lateral velocity is explicit damping 2 c_w |W - v| / m per node: on a
// bridle of 1e-9 kg/m in the 3-D bridled line's 20 m/s wind (its nodes 2.5e-10 kg) that rate, 2e8 1/s,
// is far above its band's frequency, and the lateral plane's step must hold it (it ran away in
// its first step when the limit took the band alone).
TEST(Extremes, WindDragOnAFeatherLightWire) {
  Simulation sim(load_scene_file(test_scenes::scene_path("trolley_wire_bridle_3d.yaml"), {"bridle.linear_mass=1e-9"}));
  run_finite(sim, 300);
}

// The droppers' lean couples the planes: a dropper of stiffness k leaning by s = dy0 / l ties its
// ends' heights and positions across the track through [[k, k s], [k s, T / l + k s^2]], a mode
// above either plane's own highest where the wires' elements are long. On the stitched 3-D line
// with 1 m elements and its messenger 0.5 m off the track centre (droppers leaning up to 0.74)
// that mode is 17 % above the vertical plane's: at the vertical limit's dt a standing pantograph's
// force swung between 0 and 290 N and a messenger 0.85 m off diverged. Standing, the force must
// stay at the static uplift, 100 N, to within the 3 N the design's settling moves it on the same
// line at 0.25 m elements.
TEST(Extremes, LeaningDroppersCoupleThePlanesWithinTheStep) {
  for (const char* messenger : {"[0.5]", "[0.85]"}) {
    Simulation sim(load_scene_file(test_scenes::scene_path("reference_55m_stitched_3d.yaml"),
                                   {"wind=null", "numerics.element_length=1.0", "train.speed_kmh=0", "train.start=150",
                                    std::string("stagger.messenger=") + messenger}));
    SCOPED_TRACE(std::string("messenger ") + messenger + ", dt = " + std::to_string(sim.model().dt));
    for (int k = 0; k < 10; ++k) {
      run_finite(sim, 1000);
      EXPECT_NEAR(total_contact_force(sim.model(), sim.state(), 0), 100.0, 3.0) << "after " << (k + 1) * 1000 << " steps";
    }
  }
}

// A pantograph's damper between two of its masses moves them against each other at
// c (1/m_a + 1/m_b), above either's c / m: with 1e6 N s/m between the head (7.5 kg) and the
// upper frame (9 kg), or on a head's suspension, the estimate's dt must hold (each diverged within
// 100 steps when the limit took each mass alone).
TEST(Extremes, StiffDampersBetweenPantographMasses) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"reference_55m.yaml", "pantographs.0.damping=[1.0e6, 0.0, 100.0]"},
      {"reference_55m.yaml", "pantographs.0.damping=[0.0, 1.0e6, 100.0]"},
      {"reference_55m_two_heads.yaml", "pantographs.0.heads.0.damping=1.0e6"}};
  for (const auto& [scene, damping] : cases) {
    Simulation sim(load_scene_file(test_scenes::scene_path(scene), {damping}));
    SCOPED_TRACE(scene + " " + damping + ", dt = " + std::to_string(sim.model().dt));
    run_finite(sim, 3000);
  }
}

TEST(Extremes, ElementLengthsFrom5cmTo2m) {
  for (double h : {0.05, 0.5, 2.0}) {
    Simulation sim(load_scene_file(kScene, {"numerics.element_length=" + std::to_string(h)}));
    SCOPED_TRACE("h = " + std::to_string(h));
    run_finite(sim, h < 0.1 ? 300 : 3000);
  }
}

TEST(Extremes, UpliftZeroAndFourHundredNewtons) {
  {
    // No uplift: only the roof spring (160 N/m, relaxed at the start's working height) keeps the
    // head up, so where the wire sags (presag 55 mm) the head presses at most about
    // 160 N/m x 0.055 m = 8.8 N on average; the contact is mostly lost; nothing goes NaN.
    Simulation sim(load_scene_file(kScene, {"pantographs.0.static_uplift=0"}));
    PassRecorder rec(sim.model());
    rec.record(sim.model(), sim.state());
    while (sim.step() == StepStatus::kOk) rec.record(sim.model(), sim.state());
    EXPECT_EQ(sim.state().status, StepStatus::kFinished) << sim.status_message();
    const PantographStatistics st = rec.statistics(sim.model())[0];
    EXPECT_LT(st.unfiltered.mean, 160.0 * 0.055 + 1.0);
    EXPECT_GT(st.contact_loss_percent, 50.0);
  }
  {
    Simulation sim(load_scene_file(kScene, {"pantographs.0.static_uplift=400"}));
    PassRecorder rec(sim.model());
    rec.record(sim.model(), sim.state());
    while (sim.step() == StepStatus::kOk) rec.record(sim.model(), sim.state());
    EXPECT_EQ(sim.state().status, StepStatus::kFinished) << sim.status_message();
    // Mean = uplift within the roof-spring bound (160 N/m x 0.2 m of working-height change at 400 N).
    EXPECT_NEAR(rec.statistics(sim.model())[0].filtered.mean, 400.0, 32.0);
  }
}

TEST(Extremes, SuddenSpeedAndUpliftSteps) {
  Simulation sim(load_scene_file(kScene));
  std::string err;
  run_finite(sim, 1500);
  ASSERT_TRUE(sim.set_max_acceleration(0.0, &err));  // no limit: the speed jumps
  ASSERT_TRUE(sim.set_target_speed(100.0 / 3.6, &err));
  ASSERT_TRUE(sim.set_uplift(-1, 300.0, &err));
  run_finite(sim, 1500);
  EXPECT_DOUBLE_EQ(sim.state().speed, 100.0 / 3.6);
  ASSERT_TRUE(sim.set_target_speed(400.0 / 3.6, &err));
  ASSERT_TRUE(sim.set_uplift(-1, 0.0, &err));
  run_finite(sim, 1500);
}

// A mass of next to nothing on a spring puts lambda = omega^2 beyond 1e154, where the power
// iteration's squared norm overflows (unscaled, the estimate falls to 0, and the contacts' bound
// alone would set a dt five times the line's). Two masses m on springs k (to the ground and
// between them): omega_max^2 = (k / m) (3 + sqrt 5) / 2 exactly. The iteration's error falls by
// (3 - sqrt 5) / (3 + sqrt 5) = 0.146 a step, so 1e-9 is far above what is left after it settles.
TEST(Extremes, TheStabilityEstimateHoldsForMassesOfNextToNothing) {
  for (const double m : {1.0, 1e-200, 1e-300}) {
    const double k = 1e4, inv_sqrt_m[2] = {1.0 / std::sqrt(m), 1.0 / std::sqrt(m)};
    const double w = power_iteration_omega(2, inv_sqrt_m, 3000, [k](const double* x, double* y) {
      y[0] = 2.0 * k * x[0] - k * x[1];
      y[1] = k * x[1] - k * x[0];
    });
    const double exact = std::sqrt(k / m * (3.0 + std::sqrt(5.0)) / 2.0);
    EXPECT_NEAR(w / exact, 1.0, 1e-9) << "m = " << m;
  }
}

// dt = (2 / w)(sqrt(1 + xi^2) - xi) with xi = beta w / 2 tends to 2 / (beta w^2) as xi grows (the
// stiffness damping's own limit): written as a difference it cancels to 0 once xi^2 passes
// 1/epsilon. Relative 1e-12: the quotient form loses no digits; the asymptote's error is 1/(4 xi^2).
TEST(Extremes, TheCriticalStepKeepsItsDigitsUnderHeavyStiffnessDamping) {
  const double beta = 1e-4;
  for (const double w : {1e12, 1e20, 1e100}) {
    const double xi = 0.5 * beta * w;
    EXPECT_NEAR(critical_time_step(w, 0.0, beta) / (2.0 / (beta * w * w)), 1.0, 1e-12 + 1.0 / (4.0 * xi * xi)) << "w = " << w;
  }
}
