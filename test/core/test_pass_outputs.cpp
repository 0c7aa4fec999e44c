// What PassRecorder makes of a real pass (the reference scene, 300 km/h, validation.md section 2):
// the spectrum's span-passing peak at v / span, the measuring pantograph's reconstruction, the
// droppers and steady arms against the series they come from.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

namespace {

struct Pass {
  std::unique_ptr<Simulation> sim;
  std::unique_ptr<PassRecorder> rec;
  // Independent of the recorder: every analysed dropper's force extremes, computed here.
  std::vector<double> max_force, min_force;
};

Pass run(std::vector<std::string> overrides) {
  Scene scene = load_scene_file(test_scenes::kReference, overrides);
  Pass p;
  p.sim = std::make_unique<Simulation>(scene);
  const Model& m = p.sim->model();
  p.rec = std::make_unique<PassRecorder>(m, 0.0);
  double x0 = 0.0, x1 = 0.0;
  analysis_section(m, &x0, &x1);
  std::vector<int> ids;
  for (int k : m.dropper_order)
    if (m.droppers[k].x >= x0 && m.droppers[k].x <= x1) ids.push_back(k);
  p.max_force.assign(ids.size(), -1e300);
  p.min_force.assign(ids.size(), 1e300);
  auto look = [&]() {
    const State& s = p.sim->state();
    for (std::size_t j = 0; j < ids.size(); ++j) {
      const Dropper& d = m.droppers[ids[j]];
      const double f = std::max(0.0, d.static_tension + d.stiffness * (s.u[d.messenger_dof] - s.u[d.contact_dof]));
      p.max_force[j] = std::max(p.max_force[j], f);
      p.min_force[j] = std::min(p.min_force[j], f);
    }
  };
  p.rec->record(m, p.sim->state());
  look();
  while (p.sim->step() == StepStatus::kOk) {
    p.rec->record(m, p.sim->state());
    look();
  }
  EXPECT_EQ(p.sim->state().status, StepStatus::kFinished);
  return p;
}

const Pass& reference() {
  static const Pass p = run({"train.speed_kmh=300", "output.allowed_uplift=0.05"});
  return p;
}

// The dropper pattern repeats every span, so the force of a pantograph running at v is periodic
// in time with period span / v: its spectrum has its span-passing line at v / span (the classic
// signature of a catenary's elasticity varying along the span).
TEST(PassOutputs, SpanPassingPeakSitsAtSpeedOverSpan) {
  const Pass& p = reference();
  const Model& m = p.sim->model();
  const PantographStatistics st = p.rec->statistics(m)[0];
  const double v = 300.0 / 3.6, span = 55.0;
  // The recorder's speed comes from the recorded positions and times: constant speed, so exact up
  // to rounding.
  EXPECT_NEAR(st.spectrum.span_passing_hz, v / span, 1e-9);
  EXPECT_NEAR(st.spectrum.dropper_passing_hz, v / 5.75, 1e-9);  // droppers 5.75 m apart inside a span
  ASSERT_FALSE(st.spectrum.peaks.empty());
  // A peak within one resolution (the section is ~4 s: ~0.25 Hz) of v / span, among the strongest.
  bool found = false;
  for (std::size_t i = 0; i < std::min<std::size_t>(3, st.spectrum.peaks.size()); ++i)
    found |= std::fabs(st.spectrum.peaks[i].frequency - v / span) <= st.spectrum.resolution_hz;
  EXPECT_TRUE(found) << "strongest peak at " << st.spectrum.peaks[0].frequency << " Hz, v/span " << v / span;
  EXPECT_GT(st.spectrum.resolution_hz, 0.0);
  EXPECT_LT(st.spectrum.resolution_hz, 0.5 * v / span);
}

// The reference head has no damper (damping[0] = 0): head force balance m a = F_suspension - F_c
// holds exactly at every step of the central-difference scheme, and the second difference of the
// recorded displacements is that scheme's acceleration. So the reconstruction equals the true
// force up to rounding, and low-passed at the statistics' cutoff (20 Hz both) it equals the true
// filtered force: 1e-6 N is far above the rounding (~1e-10 N) and far below any modelling slip
// (a sign or a missing preload is ~100 N, a one-step shift several N).
TEST(PassOutputs, MeasuringPantographReconstructsTheContactForce) {
  const Pass& p = reference();
  const Model& m = p.sim->model();
  const PantographStatistics st = p.rec->statistics(m)[0];
  ASSERT_TRUE(st.measured.available);
  EXPECT_EQ(st.measured.bandwidth_hz, 20.0);
  EXPECT_LT(st.measured.max_abs_difference, 1e-6);
  EXPECT_NEAR(st.measured.force.mean, st.filtered.mean, 1e-6);
  EXPECT_NEAR(st.measured.force.std_dev, st.filtered.std_dev, 1e-6);
}

// A narrower sensor smooths the force: less spread than the true force filtered at 20 Hz.
TEST(PassOutputs, NarrowSensorBandwidthSmooths) {
  const Pass p = run({"train.speed_kmh=300", "output.sensor_bandwidth=5"});
  const PantographStatistics st = p.rec->statistics(p.sim->model())[0];
  ASSERT_TRUE(st.measured.available);
  EXPECT_LT(st.measured.force.std_dev, st.filtered.std_dev);
  EXPECT_NEAR(st.measured.force.mean, st.filtered.mean, 0.5);  // a low-pass keeps the mean (ends aside)
  EXPECT_GT(st.measured.rms_difference, 0.1);
}

TEST(PassOutputs, DroppersMatchTheirForceSeries) {
  const Pass& p = reference();
  const Model& m = p.sim->model();
  const LineStatistics ls = p.rec->line_statistics(m);
  ASSERT_EQ(ls.droppers.size(), p.max_force.size());
  ASSERT_EQ(ls.droppers.size(), 6u * 9u);  // analysis section [2, 8): six spans of nine droppers
  for (std::size_t j = 0; j < ls.droppers.size(); ++j) {
    const DropperStatistics& d = ls.droppers[j];
    EXPECT_EQ(d.max_force, p.max_force[j]);
    EXPECT_EQ(d.min_force, p.min_force[j]);
    // The pass starts in the design state, where each dropper carries its static tension.
    EXPECT_LE(d.min_force, d.static_tension + 1e-9);
    EXPECT_GE(d.max_force, d.static_tension - 1e-9);
    EXPECT_EQ(d.min_force == 0.0, d.slack_percent > 0.0);
    // Rainflow never counts a range larger than the force's own span.
    EXPECT_LE(d.max_range, d.max_force - d.min_force + 1e-9);
    EXPECT_GT(d.cycles, 0.0);
    double binned = 0.0;
    for (double c : d.histogram) binned += c;
    EXPECT_DOUBLE_EQ(binned, d.cycles);  // every cycle is in a bin: the bins reach the largest range
  }
}

TEST(PassOutputs, SteadyArmsAgainstTheAllowedUplift) {
  const Pass& p = reference();
  const Model& m = p.sim->model();
  const LineStatistics ls = p.rec->line_statistics(m);
  ASSERT_EQ(ls.steady_arms.size(), 7u);  // supports 2..8 bound the section [110, 440] m
  const PantographStatistics st = p.rec->statistics(m)[0];
  double worst = 0.0;
  for (const SteadyArmStatistics& a : ls.steady_arms) {
    worst = std::max(worst, a.max_uplift);
    EXPECT_EQ(a.exceeded, a.max_uplift > 0.05);
  }
  EXPECT_DOUBLE_EQ(worst, st.max_uplift_at_support_m);  // the same arms, one pantograph
  // validation.md section 3 puts the uplift of such lines at a few cm: the flag must be able to
  // go both ways with limits either side of it.
  EXPECT_GT(worst, 0.01);
  EXPECT_LT(worst, 0.1);
}

}  // namespace
