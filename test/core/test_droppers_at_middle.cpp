// The droppers and the stitch wires' clamps at the explicit step's middle (numerics.droppers
// implicit, the fast preset on a 2-D line): the trapezoidal rule for each, with a dropper's slack
// switch decided inside the step on the tension it acts with (src/core/engine/explicit_step.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/engine/initial_state.hpp"
#include "catenary_sim/core/model/stability.hpp"
#include "catenary_sim/core/output/pass_recorder.hpp"
#include "../support/scenes.hpp"
#include "../support/stepping.hpp"

using namespace catenary_sim;

namespace {

const std::string& kDir = test_scenes::kConfigDir;
using test_stepping::run_from_static;
using test_stepping::run_to_end;

// The same model with every dropper and clamp at q_n (the supports as they were).
Model links_at_qn(const Model& m) {
  Model e = m;
  e.dropper_at_middle.assign(e.droppers.size(), 0);
  e.clamp_at_middle.assign(e.clamps.size(), 0);
  return e;
}

std::string text(double x) {
  std::ostringstream o;
  o << std::setprecision(17) << x;
  return o.str();
}

}  // namespace

// The fast preset on the reference line takes every dropper at the middle (no dropper shares a node
// with a support), and its dt is then set by the rest: beyond the explicit limit the droppers at
// q_n set, which the same model at that dt does not survive.
TEST(DroppersAtMiddle, StableBeyondTheLimitTheDroppersWouldSet) {
  const Model m = build_model(load_scene_file(kDir + "reference_55m.yaml", {"numerics.preset=fast"}));
  ASSERT_EQ(m.dropper_at_middle.size(), m.droppers.size());
  EXPECT_EQ(std::count(m.dropper_at_middle.begin(), m.dropper_at_middle.end(), 1), static_cast<long>(m.droppers.size()));
  const Model at_qn = links_at_qn(m);
  // The explicit limit with the droppers at q_n (no contact bound: a lower omega, a longer dt).
  const double limit = critical_time_step(highest_eigenfrequency(at_qn, 3000, true), m.alpha, m.beta);
  EXPECT_GT(m.dt, 1.5 * limit) << "dt " << m.dt << " s, the droppers' explicit limit " << limit << " s";
  EXPECT_EQ(run_from_static(m, 100000), StepStatus::kFinished);
  EXPECT_EQ(run_from_static(at_qn, 100000), StepStatus::kDiverged);
}

// The step is the trapezoidal rule for each dropper, with the tension-only law as a
// complementarity: from the same state, against the step with the droppers at q_n (whose dropper
// forces T_E the test recomputes: the elastic stretch's switch at q_n, eq. 19-21), every dropper
// node's m a - T at the middle equals m a_E - T_E (the rest of its force is the same), every other
// node's acceleration is the same to the bit, and each dropper's tension T (State::dropper_tension)
// is T_n + c (a_m - a_c) where positive (taut) and 0 where T_n + c (a_m - a_c) <= 0 (slack), with
// c = k (dt^2/4 + beta dt/2). Checked mid-pass (from 1 s on) at every step until slack droppers
// have been met, at 350 km/h where the pantograph lifts the line, to round-off (1e-9 of the terms).
TEST(DroppersAtMiddle, TheStepIsTheTrapezoidalRuleWithTheSlackSwitchInside) {
  const Model mid = build_model(load_scene_file(kDir + "reference_55m.yaml", {"numerics.preset=fast", "train.speed_kmh=350"}));
  const Model expl = links_at_qn(mid);
  State s = make_state(mid);
  solve_initial_state(mid, s);
  const double dt = mid.dt, beta = mid.beta;
  for (long k = 0; k < std::lround(1.0 / dt); ++k) ASSERT_EQ(step(mid, s), StepStatus::kOk);
  int slack = 0, taut = 0, steps = 0;
  ASSERT_GT(beta, 0.0);
  for (; steps < 2000 && (slack < 3 || taut < 3); ++steps) {
    State a = s, e = s;
    ASSERT_EQ(step(mid, a), StepStatus::kOk);
    ASSERT_EQ(step(expl, e), StepStatus::kOk);
    std::vector<double> t_e(mid.n_dof, 0.0), t_mid(mid.n_dof, 0.0);  // net dropper force per node
    std::vector<bool> dropper_node(mid.n_dof, false);
    for (std::size_t k = 0; k < mid.droppers.size(); ++k) {
      const Dropper& d = mid.droppers[k];
      const int m_dof = d.messenger_dof, c_dof = d.contact_dof;
      dropper_node[m_dof] = dropper_node[c_dof] = true;
      const double stretch = s.u[m_dof] - s.u[c_dof];
      const double z_stretch = stretch + beta * (s.v[m_dof] - s.v[c_dof]);
      const double te = d.static_tension + d.stiffness * stretch > 0.0 ? std::max(0.0, d.static_tension + d.stiffness * z_stretch) : 0.0;
      t_e[c_dof] += te;
      t_e[m_dof] -= te;
      const double t = a.dropper_tension[k];
      t_mid[c_dof] += t;
      t_mid[m_dof] -= t;
      const double c = d.stiffness * (0.25 * dt * dt + 0.5 * beta * dt);
      const double at_middle = d.static_tension + d.stiffness * z_stretch + c * (a.accel[m_dof] - a.accel[c_dof]);
      const double scale = d.static_tension + d.stiffness * std::fabs(z_stretch) + c * (std::fabs(a.accel[m_dof]) + std::fabs(a.accel[c_dof]));
      if (a.dropper_slack[k]) {
        ++slack;
        EXPECT_EQ(t, 0.0) << "dropper at " << d.x;
        EXPECT_LE(at_middle, 1e-9 * scale) << "slack dropper at " << d.x << ": its stretch at the middle";
      } else {
        ++taut;
        EXPECT_GT(t, 0.0) << "dropper at " << d.x;
        EXPECT_NEAR(t, at_middle, 1e-9 * scale) << "taut dropper at " << d.x;
      }
    }
    for (int i = 0; i < mid.n_dof; ++i) {
      if (!dropper_node[i]) {
        ASSERT_EQ(a.accel[i], e.accel[i]) << "DOF " << i;
        continue;
      }
      const double m = 1.0 / mid.inv_mass[i];
      const double lhs = m * a.accel[i] - t_mid[i], rhs = m * e.accel[i] - t_e[i];
      ASSERT_NEAR(lhs, rhs, 1e-9 * (std::fabs(m * a.accel[i]) + std::fabs(t_mid[i]) + std::fabs(t_e[i]))) << "DOF " << i;
    }
    s = a;
  }
  std::printf("%d steps: %d slack and %d taut dropper steps checked\n", steps, slack, taut);
  EXPECT_GE(slack, 3) << "no slack droppers met in " << steps << " steps";
  EXPECT_GE(taut, 3);
}

// Whatever the droppers' stiffness: droppers a hundred times as stiff (a node pair's frequency then
// some 10 / dt) keep the fast rung's dt and run the pass without a NaN; their damping beta k is
// centred too.
TEST(DroppersAtMiddle, StableWhateverTheDroppersStiffness) {
  const Model usual = build_model(load_scene_file(kDir + "reference_55m.yaml", {"numerics.preset=fast"}));
  const Model stiff = build_model(load_scene_file(kDir + "reference_55m.yaml", {"numerics.preset=fast", "droppers.axial_stiffness=2e7"}));
  EXPECT_NEAR(stiff.dt, usual.dt, 0.05 * usual.dt);
  EXPECT_EQ(run_from_static(stiff, 100000), StepStatus::kFinished);
}

// Second order in dt: the contact wire's height at mid-span over the first 1.5 s of a pass at
// 200 km/h on the fast rung, at dt = 4 ms (beyond the 2.2 ms the droppers at q_n allow), 2 ms and
// 1 ms, against the step with the droppers at q_n at 62.5 us (its own error far below the scheme's
// at 1 ms: it is itself second order, at 1/16 of the step). Halving dt divides a second-order error
// by 4 and a first-order one by 2; a dropper's switch is decided once per step, a first-order local
// error where one goes slack, which pulls the ratio below 4, so it is asked above 2.8 (and below 5:
// nothing converges faster than its order).
TEST(DroppersAtMiddle, ConvergeAtSecondOrderToTheExplicitStep) {
  const std::vector<std::string> base = {"numerics.preset=fast", "train.speed_kmh=200"};
  const double h1 = 0.004;
  const Model fast = build_model(load_scene_file(kDir + "reference_55m.yaml", base));
  ASSERT_GT(fast.dt, h1);
  // The contact wire's node nearest mid-span of the span the pantograph reaches after about 1 s.
  const double x = fast.train_start + 55.0 * 0.5 + 55.0;
  const Wire& cw = fast.wires[fast.contact_wires[0]];
  const int node = cw.element_at(x);
  auto trace = [&](double h, const char* droppers) {
    std::vector<std::string> o = base;
    o.push_back("numerics.dt=" + text(h));
    o.push_back(std::string("numerics.droppers=") + droppers);
    const Model m = build_model(load_scene_file(kDir + "reference_55m.yaml", o));
    std::vector<double> u;
    EXPECT_EQ(run_from_static(m, std::lround(1.5 / h), &u, m.wires[m.contact_wires[0]].w_dof + node), StepStatus::kOk);
    return u;
  };
  const std::vector<double> ref = trace(h1 / 64, "explicit");
  auto error = [&](const std::vector<double>& u, int stride) { return test_stepping::rms_against(u, ref, stride); };
  const double e1 = error(trace(h1, "implicit"), 64), e2 = error(trace(h1 / 2, "implicit"), 32);
  const double e4 = error(trace(h1 / 4, "implicit"), 16);
  std::printf("errors %.3g m at 4 ms, %.3g m at 2 ms, %.3g m at 1 ms\n", e1, e2, e4);
  EXPECT_GT(e1 / e2, 2.8) << "errors " << e1 << " m at 4 ms, " << e2 << " m at 2 ms";
  EXPECT_GT(e2 / e4, 2.8) << "errors " << e2 << " m at 2 ms, " << e4 << " m at 1 ms";
  EXPECT_LT(e1 / e2, 5.0) << "errors " << e1 << " m, " << e2 << " m";
}

// What the slack switch inside the step is for: the fast rung's dropper loads, which engineers
// size droppers by, come nearer the accurate rung's (h = 0.25 m) than with the droppers at q_n at
// the fast rung's own dt: the largest dropper force of the pass and the droppers' mean share of
// time slack, at 250 and 300 km/h. (With the switch at q_n, droppers at the middle at this dt go
// taut and slack by turns: several times the largest force, slack nearly half the time.) The
// contact force's statistics stay as near the accurate rung's as the explicit fast rung's: within
// 3 % of its standard deviation.
TEST(DroppersAtMiddle, DropperLoadsComeNearerTheFinerRung) {
  struct Loads {
    double max_force = 0.0, mean_slack = 0.0, std_force = 0.0;
  };
  auto pass = [](const std::vector<std::string>& o) {
    Simulation sim(load_scene_file(kDir + "reference_55m.yaml", o));
    PassRecorder rec(sim.model());
    rec.record(sim.model(), sim.state());
    StepStatus st = StepStatus::kOk;
    while ((st = sim.step()) == StepStatus::kOk) rec.record(sim.model(), sim.state());
    EXPECT_EQ(st, StepStatus::kFinished);
    const LineStatistics line = rec.line_statistics(sim.model());
    Loads l;
    for (const DropperStatistics& d : line.droppers) {
      l.max_force = std::max(l.max_force, d.max_force);
      l.mean_slack += d.slack_percent / line.droppers.size();
    }
    l.std_force = rec.statistics(sim.model()).at(0).filtered.std_dev;
    return l;
  };
  for (const char* kmh : {"250", "300"}) {
    SCOPED_TRACE(kmh);
    const std::string speed = std::string("train.speed_kmh=") + kmh;
    const Loads acc = pass({"numerics.preset=accurate", speed});
    const Loads mid = pass({"numerics.preset=fast", speed});
    const Loads qn = pass({"numerics.preset=fast", "numerics.droppers=explicit", "numerics.supports=explicit", speed});
    std::printf("%s km/h: largest dropper force %.0f N (accurate), %.0f N (middle), %.0f N (q_n); mean slack %.2f %%, %.2f %%, %.2f %%\n",
                kmh, acc.max_force, mid.max_force, qn.max_force, acc.mean_slack, mid.mean_slack, qn.mean_slack);
    EXPECT_LT(std::fabs(mid.max_force - acc.max_force), std::fabs(qn.max_force - acc.max_force))
        << "largest dropper force: accurate " << acc.max_force << " N, middle " << mid.max_force << " N, q_n " << qn.max_force << " N";
    EXPECT_LT(std::fabs(mid.mean_slack - acc.mean_slack), std::fabs(qn.mean_slack - acc.mean_slack))
        << "mean slack share: accurate " << acc.mean_slack << " %, middle " << mid.mean_slack << " %, q_n " << qn.mean_slack << " %";
    EXPECT_LT(std::fabs(mid.std_force - acc.std_force), 0.03 * acc.std_force)
        << "contact force std: accurate " << acc.std_force << " N, middle " << mid.std_force << " N";
  }
}

// Every shipped 2-D line at the fast and balanced rungs runs its pass (or its first 2 km on the
// endless line) without diverging with its supports, droppers and clamps at the middle, and a twin
// contact wire too. (A 3-D line keeps its droppers at q_n: mark_springs_at_middle.) The trolley
// wires' scenes choose the centred damping, with which the springs stay at q_n: here they take the
// half-step; the one on bridles has clamps and no droppers.
TEST(DroppersAtMiddle, EveryShippedLineRunsAtTheFastAndBalancedRungs) {
  const std::vector<std::string> files = {"reference_55m.yaml", "reference_55m_stitched.yaml", "compound_catenary.yaml",
                                          "reference_55m_two_sections.yaml", "reference_55m_two_pantographs.yaml",
                                          "reference_55m_two_heads.yaml", "reference_55m_endless.yaml",
                                          "trolley_wire_bridle.yaml", "catenary_to_trolley_wire.yaml"};
  for (const char* preset : {"fast", "balanced"})
    for (const std::string& f : files) {
      SCOPED_TRACE(f + " " + preset);
      std::vector<std::string> o = {std::string("numerics.preset=") + preset, "numerics.supports=implicit", "numerics.droppers=implicit"};
      if (f == "reference_55m_endless.yaml") o.push_back("train.end=2000");
      if (f.rfind("trolley", 0) == 0 || f.rfind("catenary_to_trolley", 0) == 0) o.push_back("numerics.damping=half_step");
      Simulation sim(load_scene_file(kDir + f, o));
      const Model& m = sim.model();
      EXPECT_GT(std::count(m.dropper_at_middle.begin(), m.dropper_at_middle.end(), 1) +
                    std::count(m.clamp_at_middle.begin(), m.clamp_at_middle.end(), 1),
                0);
      EXPECT_EQ(run_to_end(sim), StepStatus::kFinished) << sim.status_message();
      EXPECT_TRUE(sim.state().u.allFinite());
    }
  Simulation twin(test_scenes::twin_contact_wire({"numerics.preset=fast"}));
  EXPECT_EQ(run_to_end(twin), StepStatus::kFinished) << twin.status_message();
}

// The stitched line's clamps go to the middle with its droppers: its fast rung's dt is then no
// longer set by the clamps' 2e5 N/m on the stitch wire's light end nodes.
TEST(DroppersAtMiddle, TheStitchWiresClampsGoToTheMiddleToo) {
  const Model mid = build_model(load_scene_file(kDir + "reference_55m_stitched.yaml", {"numerics.preset=fast"}));
  ASSERT_FALSE(mid.clamps.empty());
  EXPECT_EQ(std::count(mid.clamp_at_middle.begin(), mid.clamp_at_middle.end(), 1), static_cast<long>(mid.clamps.size()));
  Model clamps_at_qn = mid;
  clamps_at_qn.clamp_at_middle.assign(mid.clamps.size(), 0);
  const double limit = critical_time_step(highest_eigenfrequency(clamps_at_qn, 3000, true), mid.alpha, mid.beta);
  EXPECT_GT(mid.dt, 1.5 * limit) << "dt " << mid.dt << " s; the clamps at q_n allow " << limit << " s";
  EXPECT_EQ(run_from_static(mid, 100000), StepStatus::kFinished);
  EXPECT_EQ(run_from_static(clamps_at_qn, 100000), StepStatus::kDiverged);
}

TEST(DroppersAtMiddle, ADropperTheWindowLeftReportsItsStaticState) {
  // With the moving window a dropper behind it is back in the static state (u = 0): what it
  // reports must be that state's elastic tension (dropper_tension NaN), not the tension it acted
  // with in its last step in the window, which a recorder would otherwise count on for the rest
  // of the pass (slack, if it left slack).
  Simulation sim(load_scene_file(kDir + "reference_55m.yaml", {"numerics.preset=fast", "numerics.window=auto"}));
  const Model& m = sim.model();
  ASSERT_FALSE(m.dropper_at_middle.empty());
  long behind = 0, inside = 0;
  while (sim.step() == StepStatus::kOk) {
    const State& s = sim.state();
    std::vector<char> in(m.droppers.size(), 0);
    for (int j = 0; j < s.window_dropper_count; ++j) in[s.window_droppers[j]] = 1;
    for (std::size_t k = 0; k < m.droppers.size(); ++k) {
      if (!m.dropper_at_middle[k]) continue;
      if (in[k]) {
        ASSERT_FALSE(std::isnan(s.dropper_tension[k])) << "dropper " << k << " in the window at t = " << s.time;
        ++inside;
      } else if (m.droppers[k].x < m.support_x[s.window_first_support]) {
        ASSERT_TRUE(std::isnan(s.dropper_tension[k])) << "dropper " << k << " behind the window at t = " << s.time;
        ++behind;
      }
    }
  }
  EXPECT_GT(behind, 1000);  // the window left droppers behind it during the pass
  EXPECT_GT(inside, 1000);
}

// Undamped high modes: with damping.beta 0 nothing damps the mesh's top modes, and a dropper whose
// slack switch is decided at q_n can feed them (docs/model_and_numerics.md, "Integrators"). One
// 60 m span with one dropper at mid-span, its contact-wire node kicked up 1 mm (enough for the
// dropper to go slack), alpha 0.0125, 20 s: the largest deflection of that node over the last
// 10 s. With the dropper at the middle the step is central differences on a mass with the
// dropper's K_I, stable by the energy method for any dt within the rest's limit, and the switch
// is decided on the tension it acts with: the kick's energy can only decay, and the deflection
// stays below the kick (measured 0.43 mm at 0.9 ms, 0.34 mm at 1.0 ms). The same span with the
// dropper at q_n at 0.9 ms reaches 75 mm: the bound separates the two by far more than any
// rounding could move it. With the reference's beta 1e-4 at q_n (the auto dt) the kick dies away.
TEST(DroppersAtMiddle, HoldAKickedSpanWithoutStiffnessDampingWhereTheSwitchAtQnPumpsIt) {
  auto late_deflection = [](double beta, const std::string& numerics) {
    const Model m = build_model(load_scene_string(
        "line: {spans: [60.0]}\n"
        "contact_wire: {linear_mass: 1.35, bending_stiffness: 195.0, tension: 22000.0}\n"
        "messenger: {linear_mass: 1.08, bending_stiffness: 131.7, tension: 16000.0}\n"
        "droppers: {positions: [30.0], axial_stiffness: 200000.0, linear_mass: 0.117}\n"
        "damping: {alpha: 0.0125, beta: " + text(beta) + "}\n"
        "numerics: " + numerics + "\n"));
    State s = make_state(m);
    solve_initial_state(m, s);
    const int node = m.wires[0].nodes() / 2;  // under the dropper
    const double rest = s.wire_uplift(m, 0, node);
    s.wire_uplift(m, 0, node) += 1e-3;
    const int steps = static_cast<int>(20.0 / m.dt);
    double late = 0.0;
    for (int k = 0; k < steps; ++k) {
      if (step(m, s) != StepStatus::kOk) return HUGE_VAL;
      if (k > steps / 2) late = std::max(late, std::fabs(s.wire_uplift(m, 0, node) - rest));
    }
    return late;
  };
  for (double dt : {0.9e-3, 1.0e-3}) {
    const double d = late_deflection(0.0, "{dt: " + text(dt) + ", safety_factor: 1.0, supports: implicit, droppers: implicit}");
    EXPECT_LT(d, 1e-3) << "droppers at the middle, beta 0, dt " << dt << " s: " << d << " m";
  }
  const double reference = late_deflection(1e-4, "{dt: auto}");
  EXPECT_LT(reference, 1e-3) << "droppers at q_n, beta 1e-4: " << reference << " m";
}
