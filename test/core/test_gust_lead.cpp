// The lateral plane's implicit gust lead (numerics.gust_lead_step implicit, src/core/engine/
// lateral_lead.cpp): the wires ahead of the lateral window stepped on their own by the trapezoidal
// rule at the wind's refresh interval, and handed over to the window as it reaches them. Its
// accuracy against the finite line's whole lateral plane is checked with the explicit lead in
// test_lateral (GustLeadGivesTheEndlessLineTheFiniteLinesTurbulentMotion).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "catenary_sim/core/model/lateral.hpp"
#include "catenary_sim/core/simulation.hpp"
#include "engine/lateral_lead.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

namespace {

// The endless reference line staggered +-0.3 m in a turbulent 20 m/s cross wind at the balanced
// rung (dt 1.55 ms), as the gust lead's bench has it.
Scene windy_endless(const std::vector<std::string>& extra) {
  std::vector<std::string> ov = {"numerics.preset=balanced", "train.start=500", "train.end=1500",
                                 "stagger.contact_wire=[0.3,-0.3]", "stagger.messenger=[0.0]", "wind.speed=20",
                                 "wind.direction=90", "wind.turbulence.intensity=0.15", "wind.turbulence.seed=2"};
  ov.insert(ov.end(), extra.begin(), extra.end());
  return load_scene_file(test_scenes::kReferenceEndless, ov);
}

// The same model with its lead stepped every `every` vertical steps.
Model with_lead_every(const Model& m, int every) {
  Model copy = m;
  auto lat = std::make_shared<LateralModel>(*m.lateral);
  set_lead_step(copy, *lat, every);
  copy.lateral = lat;
  return copy;
}

// Largest |a - b| over the lead's nodes of `s` (both at time t, lead_state_at).
double lead_difference(const Model& ma, const State& a, const Model& mb, const State& b, double t) {
  double worst = 0.0;
  for (std::size_t wi = 0; wi < ma.lateral->wires.size(); ++wi) {
    const WireWindow& ww = a.lateral.lead_window[wi];
    const int o = ma.lateral->wires[wi].w_dof;
    for (int i = ww.lo; i <= ww.hi; ++i) {
      double ya = 0, va = 0, yb = 0, vb = 0;
      lead_state_at(ma, a, o + i, t, &ya, &va);
      lead_state_at(mb, b, o + i, t, &yb, &vb);
      worst = std::max(worst, std::fabs(ya - yb));
    }
  }
  return worst;
}

}  // namespace

TEST(GustLead, ImplicitByDefaultAtTheWindsRefreshInterval) {
  Simulation sim(windy_endless({}));
  const Model& m = sim.model();
  const LateralModel& lat = *m.lateral;
  ASSERT_GT(lat.gust_lead, 0.0);
  // The field's sample time 1 / (4 max_frequency), refreshed every kWindRefreshShare of it: the
  // lead's dt is that in whole vertical steps, and the trapezoidal rule's coefficients follow.
  const double refresh = kWindRefreshShare * lat.field.dt;
  EXPECT_GE(lat.lead_every, 1);
  EXPECT_LE(lat.lead_dt, refresh + 1e-12);
  EXPECT_GT(lat.lead_dt, refresh - m.dt);
  EXPECT_DOUBLE_EQ(lat.lead_beta, 0.5 * lat.lead_dt + m.beta);
  EXPECT_DOUBLE_EQ(lat.lead_shift, (2.0 / lat.lead_dt + m.alpha) / lat.lead_beta);
  Simulation explicit_lead(windy_endless({"numerics.gust_lead_step=explicit"}));
  EXPECT_EQ(explicit_lead.model().lateral->lead_every, 0);
  // A stitched line's clamps join two wires' solves: auto keeps its lead explicit.
  Simulation stitched(load_scene_file(test_scenes::scene_path("reference_55m_stitched_3d.yaml"),
                                      {"numerics.window=auto", "numerics.gust_lead=5"}));
  ASSERT_GT(stitched.model().lateral->gust_lead, 0.0);
  EXPECT_EQ(stitched.model().lateral->lead_every, 0);
}

TEST(GustLead, HoldsTheStaticStateUnderTheMeanWind) {
  // With gusts a billionth of the mean wind the lead must stay in the static state under the mean
  // wind: every force it takes (the springs and pendulums split between the solve and the right-
  // hand side, the cuts' static force and dashpots, the held supports) must balance there. What
  // the gusts move is of order 1e-9 of the turbulent motion (centimetres): far below 1e-9 m; a
  // force left out or counted twice moves the wires by millimetres.
  Simulation sim(windy_endless({"wind.turbulence.intensity=1e-9", "train.end=900"}));
  const Model& m = sim.model();
  const LateralModel& lat = *m.lateral;
  ASSERT_GT(lat.lead_every, 0);
  double worst = 0.0;
  long compared = 0;
  while (sim.step() == StepStatus::kOk) {
    const State& s = sim.state();
    for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) {
      const WireWindow& ww = s.lateral.lead_window[wi];
      const int o = lat.wires[wi].w_dof;
      for (int i = o + ww.lo; i <= o + ww.hi; ++i) {
        worst = std::max(worst, std::fabs(s.lateral.lead_y[i] - lat.initial[i]));
        ++compared;
      }
    }
  }
  EXPECT_EQ(sim.state().status, StepStatus::kFinished) << sim.status_message();
  ASSERT_GT(compared, 1000000);
  EXPECT_LT(worst, 1e-9) << "largest departure of the lead from the static state (m)";
}

TEST(GustLead, ConvergesAtSecondOrderInItsStep) {
  // The trapezoidal rule is second order: halving the lead's step quarters its error. The finite
  // 3-D reference line windowed with a lead to its far anchor (60 s of travel), so that every node
  // in the lead has been in it from the start at rest (the nodes entering an endless line's lead
  // start at rest at the lead's own time, a first-order offset that is not the scheme's). The lead
  // stepped every 8, 4, 2 and 1 vertical steps (dt 1.55 ms at the balanced rung), compared at the
  // same instants (lead_state_at, whose linear interpolation is second order too): the differences
  // of successive pairs must fall by about 4 (at least 3: what a second-order error gives once
  // the next order is a quarter of it).
  const Scene scene = load_scene_file(test_scenes::kReference3d,
                                      {"numerics.preset=balanced", "numerics.window=auto", "numerics.gust_lead=60"});
  const Model base = Simulation(scene).model();
  ASSERT_GT(base.lateral->lead_every, 0);
  std::vector<Model> models;
  for (int every : {8, 4, 2, 1}) models.push_back(with_lead_every(base, every));
  std::vector<State> states;
  for (const Model& m : models) states.push_back(make_state(m));
  std::vector<double> worst(3, 0.0);
  for (int k = 1; k <= 1600; ++k) {
    for (std::size_t r = 0; r < models.size(); ++r) ASSERT_EQ(step(models[r], states[r]), StepStatus::kOk);
    if (k % 200 != 0) continue;
    ASSERT_EQ(states[0].lateral.lead_last_support, static_cast<int>(base.support_x.size()) - 1);
    const double t = states[0].time - base.dt;  // (every lead has stepped past it)
    for (int r = 0; r < 3; ++r)
      worst[r] = std::max(worst[r], lead_difference(models[r], states[r], models[r + 1], states[r + 1], t));
  }
  std::printf("lead every 8-4: %.3g m, 4-2: %.3g m, 2-1: %.3g m\n", worst[0], worst[1], worst[2]);
  EXPECT_GT(worst[2], 0.0);
  EXPECT_GT(worst[0] / worst[1], 3.0);
  EXPECT_GT(worst[1] / worst[2], 3.0);
}

TEST(GustLead, SkinsSeeTheLeadsWires) {
  // The wires a skin draws (lateral_position): in the window the lateral state, in the implicit
  // lead the lead's state at the state's time (the lateral state holds the static state there).
  Simulation sim(windy_endless({"train.end=900"}));
  const Model& m = sim.model();
  const LateralModel& lat = *m.lateral;
  for (int k = 0; k < 1200; ++k) ASSERT_EQ(sim.step(), StepStatus::kOk);
  const State& s = sim.state();
  double moved = 0.0;
  int checked = 0;
  for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) {
    const int o = lat.wires[wi].w_dof;
    const WireWindow &win = s.lateral.window[wi], &lead = s.lateral.lead_window[wi];
    ASSERT_LT(win.lo, win.hi);
    ASSERT_EQ(lead.lo, win.hi);  // the lead from the window's front support on
    for (int i = win.lo; i <= win.hi; ++i) EXPECT_EQ(lateral_position(m, s, o + i), s.lateral.y[o + i]);
    for (int i = lead.lo + 1; i <= lead.hi; ++i) {
      double y = 0.0, v = 0.0;
      lead_state_at(m, s, o + i, s.time, &y, &v);
      EXPECT_EQ(lateral_position(m, s, o + i), y);
      EXPECT_EQ(s.lateral.y[o + i], lat.initial[o + i]);
      moved = std::max(moved, std::fabs(y - lat.initial[o + i]));
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
  EXPECT_GT(moved, 1e-3);  // the gusts move the lead's wires by millimetres in 1.9 s
}

TEST(GustLead, AResetThatKeepsTheTimeRestartsTheLeadThere) {
  // Simulation::reset keeps the clock by default, and the initial state's lead is at time 0: the
  // lead must go on from the reset state at the clock's time, not step the whole time since 0 (a
  // live node reset after an hour would stall for minutes).
  Simulation sim(windy_endless({}));
  const Model& m = sim.model();
  for (int k = 0; k < 1501; ++k) ASSERT_EQ(sim.step(), StepStatus::kOk);  // (not a whole number of lead steps)
  ASSERT_NE(1501 % m.lateral->lead_every, 0);
  const double t = sim.state().time;
  sim.reset();
  ASSERT_EQ(sim.state().time, t);
  ASSERT_EQ(sim.step(), StepStatus::kOk);
  const LateralState& ls = sim.state().lateral;
  // One vertical step later the lead restarted at the reset's time (the step's start), without a
  // step for the time it missed (from 0 its steps would end elsewhere in its grid), and is in the
  // static state (the reset's).
  EXPECT_NEAR(ls.lead_time, t, 1e-9);
  double worst = 0.0;
  for (std::size_t wi = 0; wi < m.lateral->wires.size(); ++wi) {
    const WireWindow& ww = ls.lead_window[wi];
    const int o = m.lateral->wires[wi].w_dof;
    for (int i = o + ww.lo; i <= o + ww.hi; ++i) worst = std::max(worst, std::fabs(ls.lead_y[i] - m.lateral->initial[i]));
  }
  EXPECT_LT(worst, 1e-4);  // a step of gusts moves the wires by micrometres, 2 s of them by millimetres
}
