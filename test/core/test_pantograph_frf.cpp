// The pantograph model's frequency response at the head: the analytic transfer function (eq. 9 in
// the frequency domain) against closed forms, and the simulated rig (stepped sines on a rigid
// wire, the force read from the contact) against the analytic one.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>

#include "catenary_sim/core/analysis/pantograph_frf.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

namespace {
constexpr double kPi = 3.14159265358979323846;

std::vector<double> log_frequencies(double f0, double f1, int n) {
  std::vector<double> f;
  for (int i = 0; i < n; ++i) f.push_back(f0 * std::pow(f1 / f0, static_cast<double>(i) / (n - 1)));
  return f;
}
}  // namespace

// One mass on a spring and a damper to the roof: H = 1 / (k - w^2 m + i w c), whatever k0 drives
// it (the driven set-up only adds the contact spring between drive and head, which X/F skips).
TEST(PantographFrf, OneMassMatchesTheClosedForm) {
  Scene scene = load_scene_file(test_scenes::kCalpeExample);
  PantographSpec& p = scene.pantographs[0];
  p.masses = {10.0};
  p.stiffness = {3000.0};
  p.damping = {40.0};
  for (double k0 : {5e4, 2e5}) {
    scene.contact.stiffness = k0;
    const Model rig = build_model(frf_rig_scene(scene, 0, 1e-4));
    const std::vector<double> f = log_frequencies(0.1, 20.0, 15);
    const std::vector<FrfPoint> a = analytic_frf(rig, 0, f);
    for (std::size_t i = 0; i < f.size(); ++i) {
      const double w = 2 * kPi * f[i];
      const std::complex<double> h = 1.0 / std::complex<double>(3000.0 - w * w * 10.0, w * 40.0);
      // Round-off of a 1x1 complex solve and a subtraction k0 (x - 1) of order 1 (k0 x ~ k0):
      // relative 1e-9 leaves a wide margin over double precision.
      EXPECT_LT(std::abs(a[i].receptance / h - 1.0), 1e-9) << f[i] << " Hz, k0 " << k0;
      EXPECT_LT(std::abs(a[i].apparent_mass * (-w * w * h) - 1.0), 1e-9) << f[i] << " Hz";
    }
  }
}

// The simulated rig against the analytic FRF, 0.5-20 Hz. The explicit scheme takes the dampers
// with the half-step velocity v_{n-1/2} (eq. 19-21): for a harmonic motion a lag of dt/2, a
// phase error w dt/2 on the damping force, so |H_sim / H - 1| <= w dt / 2 (the damping force is
// at most the whole dynamic force); the central differences' own frequency error (w dt)^2 / 12
// is below 1.3e-5 here. The drive settles until the slowest free transient is below 1e-4 of its
// size (FrfMeasurement::settle_tolerance): 2e-4 for it in X and F. Bound: w dt / 2 + 2e-4.
TEST(PantographFrf, SimulatedRigMatchesTheAnalyticTransferFunction) {
  const Scene scene = load_scene_file(test_scenes::kCalpeExample);
  const double dt = 1e-4;
  const Model rig = build_model(frf_rig_scene(scene, 0, dt));
  ASSERT_DOUBLE_EQ(rig.dt, dt);
  const std::vector<double> f = log_frequencies(0.5, 20.0, 12);
  FrfMeasurement how;
  ASSERT_GT(slowest_decay_rate(rig, 0) * how.max_settle_time, std::log(1.0 / how.settle_tolerance))
      << "the settling is capped: the bound below would not hold";
  const std::vector<FrfPoint> a = analytic_frf(rig, 0, f), s = measured_frf(rig, f, how);
  for (std::size_t i = 0; i < f.size(); ++i) {
    const double w = 2 * kPi * f[i], bound = w * dt / 2 + 2 * how.settle_tolerance;
    const std::complex<double> ratio = s[i].receptance / a[i].receptance;
    EXPECT_LT(std::abs(std::abs(ratio) - 1.0), bound) << "magnitude at " << f[i] << " Hz";
    EXPECT_LT(std::abs(std::arg(ratio)), bound) << "phase at " << f[i] << " Hz";
    EXPECT_LT(std::abs(std::abs(s[i].apparent_mass / a[i].apparent_mass) - 1.0), bound) << f[i] << " Hz";
  }
}

// The error above is the scheme's, not the settling's: it is first order in dt (the damper's
// half-step lag), so halving dt halves it (ratio 2 within 20 %).
TEST(PantographFrf, RigErrorIsFirstOrderInTheTimeStep) {
  const Scene scene = load_scene_file(test_scenes::kCalpeExample);
  const std::vector<double> f = {1.0, 2.5, 4.0};
  double err[2] = {0, 0};
  const double dts[2] = {2e-4, 1e-4};
  for (int k = 0; k < 2; ++k) {
    const Model rig = build_model(frf_rig_scene(scene, 0, dts[k]));
    FrfMeasurement how;
    how.settle_tolerance = 1e-6;  // transients far below the scheme's error
    const std::vector<FrfPoint> a = analytic_frf(rig, 0, f), s = measured_frf(rig, f, how);
    for (std::size_t i = 0; i < f.size(); ++i) err[k] = std::max(err[k], std::abs(s[i].receptance / a[i].receptance - 1.0));
  }
  EXPECT_GT(err[0] / err[1], 1.6);
  EXPECT_LT(err[0] / err[1], 2.4);
}

TEST(PantographFrf, MovingForceHasNoFrequencyResponse) {
  Scene scene = load_scene_file(test_scenes::kCalpeExample);
  scene.pantographs[0].moving_force = true;
  const Model rig = build_model(frf_rig_scene(scene, 0, 1e-4));
  try {
    analytic_frf(rig, 0, {1.0});
    FAIL() << "no error";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("moving force"), std::string::npos) << e.what();
  }
}
