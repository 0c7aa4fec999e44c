// The reference scene (validation.md section 2) at 250 and 300 km/h: physically plausible
// statistics, and the pantograph's impulse balance, which ties the reported contact force to the
// forces that actually moved the pantograph.
#include <gtest/gtest.h>

#include <cmath>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

namespace {

struct PassResult {
  PantographStatistics stats;
  double impulse_error = 0.0;  // relative
  double static_uplift_support_m = 0.0;
};

PassResult run_pass(double speed_kmh) {
  Scene scene = load_scene_file(test_scenes::kReference);
  scene.train_speed = speed_kmh / 3.6;
  Simulation sim(scene);
  const Model& m = sim.model();
  const Pantograph& p = m.pantographs[0];
  PassRecorder rec(m);
  rec.record(m, sim.state());
  // Impulse balance of the pantograph: sum_i m_i (v_i(end) - v_i(0)) = sum_n dt (F0 + C_roof - F_contact),
  // exact for the central-difference update (internal springs cancel).
  const int last = p.masses_count() - 1;  // the lowest mass, on the roof spring
  double impulse = 0.0, contact_impulse = 0.0;
  while (true) {
    const State& s = sim.state();
    const double roof = p.spring_preload.back() - p.stiffness.back() * s.pantograph_displacement(m, 0, last) -
                        p.damping.back() * s.pantograph_velocity(m, 0, last);
    const double uplift = s.uplift[0];
    const double contact = total_contact_force(m, s, 0);  // the force step() applies (eq. 22 at t_n)
    if (sim.step() != StepStatus::kOk) break;
    impulse += m.dt * (uplift + roof - contact);
    contact_impulse += m.dt * contact;
    rec.record(m, sim.state());
  }
  EXPECT_EQ(sim.state().status, StepStatus::kFinished) << sim.status_message();
  double momentum = 0.0;
  for (int i = 0; i < p.masses_count(); ++i) momentum += p.masses[i] * sim.state().pantograph_velocity(m, 0, i);
  PassResult r;
  r.stats = rec.statistics(m)[0];
  r.impulse_error = std::fabs(momentum - impulse) / contact_impulse;
  return r;
}

void expect_plausible(const PassResult& r, double static_uplift) {
  const ForceStatistics& f = r.stats.filtered;
  for (double v : {f.mean, f.std_dev, f.max, f.min, r.stats.contact_loss_percent, r.stats.max_uplift_at_support_m})
    EXPECT_TRUE(std::isfinite(v));
  // Time-averaging the pantograph's equations, mean(F_contact) = F0 + mean(roof spring force):
  // the roof spring (160 N/m) is relaxed at the start, and the head's mean working height over
  // the section differs from it by at most the static uplift of the wire (< 0.05 m under 100 N,
  // the elasticity of this catenary is below 0.5 mm/N), so |mean - F0| < 160 * 0.05 = 8 N.
  EXPECT_NEAR(f.mean, static_uplift, 8.0);
  // The wave and span-passing excitations give a dynamic spread of tens of newtons; a spread
  // below 5 N or above the mean itself would mean the excitation is missing or the pass unstable.
  EXPECT_GT(f.std_dev, 5.0);
  EXPECT_LT(f.std_dev, f.mean);
  EXPECT_GT(f.max, f.mean);
  EXPECT_LT(f.min, f.mean);
  // Steady arms rise under a passing pantograph, by centimetres at most.
  EXPECT_GT(r.stats.max_uplift_at_support_m, 0.0);
  EXPECT_LT(r.stats.max_uplift_at_support_m, 0.2);
  // Rounding only: the impulse balance holds exactly for the discrete update.
  EXPECT_LT(r.impulse_error, 1e-9);
}

}  // namespace

TEST(ReferencePass, PlausibleAt250And300KmhAndSpreadGrowsWithSpeed) {
  const PassResult r250 = run_pass(250.0), r300 = run_pass(300.0);
  expect_plausible(r250, 100.0);
  expect_plausible(r300, 100.0);
  // Known physics (and the trend of EN 50318's ranges, 26-31 N -> 32-40 N): the standard
  // deviation grows with speed in this range.
  EXPECT_GT(r300.stats.filtered.std_dev, r250.stats.filtered.std_dev);
  std::printf("250 km/h: mean %.1f std %.1f max %.1f min %.1f loss %.2f%% uplift %.1f mm\n", r250.stats.filtered.mean,
              r250.stats.filtered.std_dev, r250.stats.filtered.max, r250.stats.filtered.min,
              r250.stats.contact_loss_percent, 1e3 * r250.stats.max_uplift_at_support_m);
  std::printf("300 km/h: mean %.1f std %.1f max %.1f min %.1f loss %.2f%% uplift %.1f mm\n", r300.stats.filtered.mean,
              r300.stats.filtered.std_dev, r300.stats.filtered.max, r300.stats.filtered.min,
              r300.stats.contact_loss_percent, 1e3 * r300.stats.max_uplift_at_support_m);
}

TEST(Filter, ButterworthPassesLowAndStopsHighFrequencies) {
  // A 4th-order Butterworth run twice has gain |H|^2 = 1 / (1 + (f/fc)^8): 0.996 at fc/2 and
  // 1/257 at 2 fc; test away from the ends, where the padding could matter.
  const double fs = 1000.0, fc = 20.0;
  for (const auto& [f, gain] : {std::pair<double, double>{10.0, 1.0 / (1.0 + std::pow(0.5, 8))},
                                std::pair<double, double>{40.0, 1.0 / (1.0 + std::pow(2.0, 8))}}) {
    std::vector<double> x(4000);
    for (std::size_t i = 0; i < x.size(); ++i) x[i] = std::sin(2 * M_PI * f * i / fs);
    const std::vector<double> y = lowpass_zero_phase(x, fs, fc);
    double peak = 0.0, lag_err = 0.0;
    for (std::size_t i = 1000; i < 3000; ++i) {
      peak = std::max(peak, std::fabs(y[i]));
      lag_err = std::max(lag_err, std::fabs(y[i] - gain * x[i]));  // zero phase: y is x scaled
    }
    EXPECT_NEAR(peak, gain, 0.01 * gain + 1e-4);
    EXPECT_LT(lag_err, 0.02 * gain + 1e-4);
  }
}
