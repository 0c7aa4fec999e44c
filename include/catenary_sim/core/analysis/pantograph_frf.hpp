// The pantograph model's frequency response at its head, as a laboratory measures a real one
// (apparent mass or receptance, 0-20 Hz): from the model's equations (eq. 9, linear, solved in
// the frequency domain) and measured in the simulator (the pantograph alone under a rigid contact
// wire driven by stepped sines; the force read from the contact, eq. 22).
#pragma once

#include <Eigen/Core>
#include <complex>
#include <functional>
#include <string>
#include <vector>

#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

// One frequency of a head FRF. The head displacement is the mean of the masses the collectors
// act on (the head itself for a one-head pantograph), the force the one applied to them (the
// contact force, downward, taken positive upward on the head: receptance = X / F).
struct FrfPoint {
  double frequency = 0.0;                 // Hz
  std::complex<double> receptance;        // m/N, X / F
  std::complex<double> apparent_mass;     // kg, F / A = -1 / (w^2 receptance)
  double drive_amplitude = 0.0;           // m, rigid wire amplitude (measured only)
  double settle_time = 0.0;               // s, simulated before the measurement window (measured only)
};

// The pantograph's linear equations (eq. 9): DOFs in the model's order from its first DOF;
// `contact` holds, per collector, the DOF (index into these matrices) it presses on.
struct PantographSystem {
  Eigen::MatrixXd mass, stiffness, damping;
  std::vector<int> contact;
};
PantographSystem pantograph_system(const Model& model, int pantograph);

// Analytic FRF at the head with the heads driven together through the contact springs k0 by a
// rigid wire (the measurement's set-up): for one head X / F is the pantograph's own receptance,
// independent of k0.
std::vector<FrfPoint> analytic_frf(const Model& model, int pantograph, const std::vector<double>& frequencies);

struct FrfMeasurement {
  double dt = 1e-4;                 // s, time step of the simulated rig
  double force_share = 0.5;         // dynamic force amplitude as a share of the static uplift (keeps contact)
  double settle_tolerance = 1e-4;   // free transient left at the window's start, as a share of its size
  int ramp_periods = 3;             // raised-cosine ramp of the drive amplitude
  int window_periods = 4;           // periods fitted (least squares: mean, cosine, sine)
  double max_settle_time = 120.0;   // s, per frequency
  // Called now and then during the run with the steps done and the steps of the whole
  // measurement (frf_steps), for a progress line: a small --dt runs for hours.
  std::function<void(long long done, long long total)> progress;
  long long progress_every = 1LL << 22;  // steps between calls
};

// The steps measured_frf takes for these frequencies (ramp, settling and window of each), known
// before running it: lets a tool refuse a --dt that would run for hours.
long long frf_steps(const Model& rig, const std::vector<double>& frequencies, const FrfMeasurement& how);

// The rig: a copy of `scene` with only `pantograph` (at position 0), under a short single contact
// wire at speed 0; the contact (stiffness, rub length) is the scene's.
Scene frf_rig_scene(const Scene& scene, int pantograph, double dt);

// Stepped sines on the rig (built from frf_rig_scene): every contact-wire node is moved as one
// rigid body, y = Y sin(w t) after a ramp, the pantograph integrated by step() (the scene's
// integrator), and the head displacement and the contact force fitted over whole periods once the
// slowest free transient of the driven pantograph has decayed below `settle_tolerance`.
// Throws SceneError if the head loses contact (amplitude too large for the static uplift).
std::vector<FrfPoint> measured_frf(const Model& rig, const std::vector<double>& frequencies, const FrfMeasurement& how);

// Slowest decay rate (1/s) of the pantograph's free motion with its collectors held by k0 to a
// still wire: -max Re(lambda) of the state matrix.
double slowest_decay_rate(const Model& model, int pantograph);

}  // namespace catenary_sim
