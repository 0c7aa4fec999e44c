// The supports' springs at the explicit step's middle (numerics.supports implicit): the step is then central differences on the mass M + (dt^2/4 + beta dt/2) K_S,
// stable for dt below 2 / omega_max of the rest alone, and still second order in dt
// (src/core/engine/explicit_step.cpp). The droppers stay at q_n here (test_droppers_at_middle takes
// them to the middle too).
#include <gtest/gtest.h>

#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/engine/initial_state.hpp"
#include "catenary_sim/core/model/stability.hpp"
#include "../support/scenes.hpp"
#include "../support/stepping.hpp"

using namespace catenary_sim;

namespace {

const std::string& kDir = test_scenes::kConfigDir;
using test_stepping::run_from_static;
using test_stepping::run_to_end;

// The contact wire's DOF at the steady arm nearest station x.
int steady_arm_dof(const Model& m, double x) {
  int best = -1;
  double gap = 1e300;
  for (const SupportSpring& sp : m.springs)
    if (sp.steady_arm && std::fabs(sp.x - x) < gap) gap = std::fabs(sp.x - x), best = sp.dof;
  return best;
}

}  // namespace

// Supports ten times the reference's (5e6 N/m on the messenger) on the fast rung's 1 m elements
// would bound dt at about 0.7 ms taken at q_n; at the step's middle they do not: the rung's dt
// is set by the droppers (2.5 ms) and lies well beyond the explicit limit of the whole system, and
// the pass runs to its end. The same model with the supports at q_n at that dt diverges, so the
// stability is the scheme's, not the scene's. The estimate of the rest is a bound: the pass runs
// at the estimate itself too.
TEST(SupportsAtMiddle, StableBeyondTheLimitTheSupportsWouldSet) {
  const std::vector<std::string> stiff = {"numerics.preset=fast", "numerics.supports=implicit", "numerics.droppers=explicit", "messenger_supports.stiffness=5e6"};
  const Model m = build_model(load_scene_file(kDir + "reference_55m.yaml", stiff));
  ASSERT_EQ(m.support_at_middle.size(), m.springs.size());
  for (std::size_t k = 0; k < m.springs.size(); ++k)
    EXPECT_EQ(m.support_at_middle[k] != 0, m.inv_mass[m.springs[k].dof] > 0.0) << "support " << k;
  // The explicit limit with the supports at q_n (no contact bound: a lower omega, a longer dt).
  const double whole = critical_time_step(highest_eigenfrequency(m), m.alpha, m.beta);
  EXPECT_GT(m.dt, 2.0 * whole) << "dt " << m.dt << " s, the whole system's explicit limit " << whole << " s";
  EXPECT_EQ(run_from_static(m, 100000), StepStatus::kFinished);
  Model all_explicit = m;  // the same dt with the supports at q_n
  all_explicit.support_at_middle.assign(m.springs.size(), 0);
  EXPECT_EQ(run_from_static(all_explicit, 100000), StepStatus::kDiverged);
  std::vector<std::string> at_estimate = stiff;
  at_estimate.push_back("numerics.safety_factor=1");
  EXPECT_EQ(run_from_static(build_model(load_scene_file(kDir + "reference_55m.yaml", at_estimate)), 100000), StepStatus::kFinished);
}

// The correction is the trapezoidal rule: from the same state, the step with the supports at the
// middle gives the accelerations a with (m + c) a = m a_E on each support's node, a_E the explicit
// step's and c = k (dt^2/4 + beta dt/2) (the stiffness at (q_{n+1} + 2 q_n + q_{n-1}) / 4 and the
// damping at (v_{n+1/2} + v_{n-1/2}) / 2, written out in explicit_step.cpp); every other node as
// the explicit step. Checked to round-off (1e-9 of the terms) mid-pass, the pantograph under the
// line.
TEST(SupportsAtMiddle, TheCorrectionIsTheTrapezoidalRule) {
  const Model mid = build_model(load_scene_file(kDir + "reference_55m.yaml", {"numerics.preset=fast", "numerics.supports=implicit", "numerics.droppers=explicit"}));
  Model expl = mid;
  expl.support_at_middle.assign(mid.springs.size(), 0);
  State s = make_state(mid);
  solve_initial_state(mid, s);
  for (int k = 0; k < 600; ++k) ASSERT_EQ(step(mid, s), StepStatus::kOk);
  State a = s, e = s;
  ASSERT_EQ(step(mid, a), StepStatus::kOk);
  ASSERT_EQ(step(expl, e), StepStatus::kOk);
  const double dt = mid.dt, beta = mid.beta;
  ASSERT_GT(beta, 0.0);
  std::vector<bool> corrected(mid.n_dof, false);
  for (const SupportSpring& sp : mid.springs) {
    const int i = sp.dof;
    if (!(mid.inv_mass[i] > 0.0)) continue;
    corrected[i] = true;
    const double m = 1.0 / mid.inv_mass[i], c = sp.stiffness * (0.25 * dt * dt + 0.5 * beta * dt);
    const double lhs = (m + c) * a.accel[i], rhs = m * e.accel[i];
    EXPECT_NEAR(lhs, rhs, 1e-9 * (std::fabs(rhs) + c * std::fabs(a.accel[i]))) << "support at " << sp.x;
  }
  int others = 0;
  for (int i = 0; i < mid.n_dof; ++i)
    if (!corrected[i]) {
      ++others;
      ASSERT_EQ(a.accel[i], e.accel[i]) << "DOF " << i;
    }
  EXPECT_GT(others, 0);
}

// Whatever the supports' stiffness: supports of 1e9 N/m (a node's frequency then far beyond 2 / dt)
// keep the fast rung's dt and run. Their damping beta k is centred too: taken at v_{n-1/2} alone it
// would need dt below (2 / omega)(sqrt(1 + xi^2) - xi) with omega near 2 / dt, which fails.
TEST(SupportsAtMiddle, StableWhateverTheSupportsStiffness) {
  const std::vector<std::string> o = {"numerics.preset=fast", "numerics.supports=implicit", "numerics.droppers=explicit", "messenger_supports.stiffness=1e9",
                                      "steady_arms.stiffness=1e9"};
  const Model stiff = build_model(load_scene_file(kDir + "reference_55m.yaml", o));
  const Model usual = build_model(load_scene_file(kDir + "reference_55m.yaml", {"numerics.preset=fast", "numerics.supports=implicit", "numerics.droppers=explicit"}));
  EXPECT_NEAR(stiff.dt, usual.dt, 0.05 * usual.dt);  // (the contact's bound moves a little with the arms)
  EXPECT_EQ(run_from_static(stiff, 100000), StepStatus::kFinished);
}

// Second order in dt, and no less accurate than the explicit step: the uplift at a steady arm over
// the first 1.5 s of a pass at 200 km/h (the pantograph passes two supports) on the fast rung with
// supports of 5e6 N/m, at dt = 2 ms (beyond the 0.78 ms the supports at q_n allow), 1 ms and 0.5 ms,
// against the explicit step at 62.5 us (its own error some 1/60 of the scheme's at 0.5 ms).
// Halving dt divides a second-order error by 4 and a first-order one by 2; droppers going slack
// are switched at a step, a local error of first order at each switch, which pulls the ratio below
// 4, so it is asked above 2.8 (and below 5: nothing converges faster than its order). At 0.5 ms,
// where the explicit step is stable too, the supports at the middle may add at most half of that
// step's own error.
TEST(SupportsAtMiddle, ConvergeAtSecondOrderToTheExplicitStep) {
  const std::vector<std::string> base = {"numerics.preset=fast", "numerics.supports=implicit", "numerics.droppers=explicit", "train.speed_kmh=200", "messenger_supports.stiffness=5e6"};
  const double h1 = 0.002;
  ASSERT_GT(build_model(load_scene_file(kDir + "reference_55m.yaml", base)).dt, h1);
  auto trace = [&](double h, const char* supports) {
    std::vector<std::string> o = base;
    std::ostringstream dt_text;
    dt_text << std::setprecision(17) << h;
    o.push_back("numerics.dt=" + dt_text.str());
    o.push_back(std::string("numerics.supports=") + supports);
    const Model m = build_model(load_scene_file(kDir + "reference_55m.yaml", o));
    std::vector<double> u;
    EXPECT_EQ(run_from_static(m, std::lround(1.5 / h), &u, steady_arm_dof(m, 110.0 + 55.0)), StepStatus::kOk);
    return u;
  };
  const std::vector<double> ref = trace(h1 / 32, "explicit");
  auto error = [&](const std::vector<double>& u, int stride) { return test_stepping::rms_against(u, ref, stride); };
  const double e1 = error(trace(h1, "implicit"), 32), e2 = error(trace(h1 / 2, "implicit"), 16);
  const double e4 = error(trace(h1 / 4, "implicit"), 8), explicit4 = error(trace(h1 / 4, "explicit"), 8);
  EXPECT_GT(e1 / e2, 2.8) << "errors " << e1 << " m at 2 ms, " << e2 << " m at 1 ms";
  EXPECT_GT(e2 / e4, 2.8) << "errors " << e2 << " m at 1 ms, " << e4 << " m at 0.5 ms";
  EXPECT_LT(e1 / e2, 5.0) << "errors " << e1 << " m, " << e2 << " m";
  EXPECT_LT(e4, 1.5 * explicit4) << "at 0.5 ms: " << e4 << " m, the explicit step " << explicit4 << " m";
}

// Every shipped line at the fast and balanced rungs runs its pass (or its first 2 km on the
// endless line) without diverging, and a twin contact wire too.
TEST(SupportsAtMiddle, EveryShippedLineRunsAtTheFastAndBalancedRungs) {
  const std::vector<std::string> files = {"reference_55m.yaml",  "reference_55m_stitched.yaml", "reference_55m_stitched_3d.yaml",
                                          "compound_catenary.yaml", "compound_catenary_3d.yaml", "reference_55m_two_sections.yaml",
                                          "reference_55m_two_pantographs.yaml", "reference_55m_two_heads.yaml",
                                          "reference_55m_3d.yaml", "reference_55m_hinged_arms.yaml", "reference_55m_3d_hinged_arms.yaml",
                                          "reference_55m_endless.yaml"};  // (the rail's scenes: centred damping)
  for (const char* preset : {"fast", "balanced"})
    for (const std::string& f : files) {
      SCOPED_TRACE(f + " " + preset);
      std::vector<std::string> o = {std::string("numerics.preset=") + preset, "numerics.supports=implicit", "numerics.droppers=explicit"};
      if (f == "reference_55m_endless.yaml") o.push_back("train.end=2000");
      Simulation sim(load_scene_file(kDir + f, o));
      EXPECT_EQ(run_to_end(sim), StepStatus::kFinished) << sim.status_message();
      EXPECT_TRUE(sim.state().u.allFinite());
    }
  Simulation twin(test_scenes::twin_contact_wire({"numerics.preset=fast", "numerics.supports=implicit", "numerics.droppers=explicit"}));
  EXPECT_EQ(run_to_end(twin), StepStatus::kFinished) << twin.status_message();
}
