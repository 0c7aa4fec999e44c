// The pantograph's frequency response at the head: analytic (eq. 9 in the frequency domain) and
// measured on a simulated rig (stepped sines, the force read from the contact, eq. 22).
#include "util/format.hpp"
#include "catenary_sim/core/analysis/pantograph_frf.hpp"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "catenary_sim/core/engine/state.hpp"

namespace catenary_sim {

namespace {

constexpr double kPi = 3.14159265358979323846;


// Adds a spring (or damper) of value k between local DOFs a and b (b < 0: the roof).
void add_link(Eigen::MatrixXd& k, int a, int b, double value) {
  k(a, a) += value;
  if (b < 0) return;
  k(b, b) += value;
  k(a, b) -= value;
  k(b, a) -= value;
}

// Static force on the pantograph's DOFs at displacement 0 without the contact: spring preloads
// and the uplift on the lowest frame mass (as assemble_force in engine/step.cpp; the rig runs at
// speed 0, so no aerodynamic terms).
Eigen::VectorXd preload_force(const Model& m, int pi, double uplift) {
  const Pantograph& p = m.pantographs[pi];
  const int n = p.masses_count();
  Eigen::VectorXd f = Eigen::VectorXd::Zero(p.dof_count());
  for (int i = 0; i < n; ++i) {
    f[i] += p.spring_preload[i];
    if (i + 1 < n) f[i + 1] -= p.spring_preload[i];
  }
  f[n - 1] += uplift;
  for (const Head& h : p.heads) {
    f[h.dof - p.first_dof] += h.preload;
    f[0] -= h.preload;
  }
  return f;
}

// The driven rig's dynamic matrix K + k0 sum e_c e_c^T - w^2 M + i w C and its right-hand side
// per unit drive amplitude, k0 sum e_c.
void driven_system(const Model& m, const PantographSystem& sys, double w, Eigen::MatrixXcd* a, Eigen::VectorXcd* b) {
  const int n = static_cast<int>(sys.mass.rows());
  const std::complex<double> iw(0.0, w);
  *a = (sys.stiffness - w * w * sys.mass).cast<std::complex<double>>() + iw * sys.damping.cast<std::complex<double>>();
  *b = Eigen::VectorXcd::Zero(n);
  for (int c : sys.contact) {
    (*a)(c, c) += m.contact_stiffness;
    (*b)[c] += m.contact_stiffness;
  }
}

}  // namespace

PantographSystem pantograph_system(const Model& m, int pi) {
  const Pantograph& p = m.pantographs.at(pi);
  if (p.moving_force) throw SceneError("pantograph '" + p.name + "': a moving force has no masses, hence no frequency response");
  const int n = p.dof_count();
  PantographSystem s;
  s.mass = Eigen::MatrixXd::Zero(n, n);
  s.stiffness = Eigen::MatrixXd::Zero(n, n);
  s.damping = Eigen::MatrixXd::Zero(n, n);
  const int nm = p.masses_count();
  for (int i = 0; i < nm; ++i) {
    s.mass(i, i) = p.masses[i];
    const int below = i + 1 < nm ? i + 1 : -1;  // eq. 9: mass i on spring i to the mass below (the roof last)
    add_link(s.stiffness, i, below, p.stiffness[i]);
    add_link(s.damping, i, below, p.damping[i]);
  }
  for (const Head& h : p.heads) {  // each head on its suspension to the top frame mass
    const int a = h.dof - p.first_dof;
    s.mass(a, a) = h.mass;
    add_link(s.stiffness, a, 0, h.stiffness);
    add_link(s.damping, a, 0, h.damping);
  }
  for (int ci : p.collectors) s.contact.push_back(m.collectors[ci].dof - p.first_dof);
  return s;
}

std::vector<FrfPoint> analytic_frf(const Model& m, int pi, const std::vector<double>& frequencies) {
  const PantographSystem sys = pantograph_system(m, pi);
  std::vector<FrfPoint> out;
  for (double f : frequencies) {
    const double w = 2.0 * kPi * f;
    Eigen::MatrixXcd a;
    Eigen::VectorXcd b;
    driven_system(m, sys, w, &a, &b);
    const Eigen::VectorXcd x = a.partialPivLu().solve(b);  // drive amplitude 1 m
    std::complex<double> head = 0.0, contact = 0.0;
    for (int c : sys.contact) {
      head += x[c];
      contact += m.contact_stiffness * (x[c] - 1.0);  // eq. 22: k0 (head - wire)
    }
    head /= static_cast<double>(sys.contact.size());
    FrfPoint p;
    p.frequency = f;
    p.receptance = head / -contact;  // the contact pushes the head down
    p.apparent_mass = -1.0 / (w * w * p.receptance);
    out.push_back(p);
  }
  return out;
}

double slowest_decay_rate(const Model& m, int pi) {
  const PantographSystem sys = pantograph_system(m, pi);
  const int n = static_cast<int>(sys.mass.rows());
  Eigen::MatrixXd k = sys.stiffness;
  for (int c : sys.contact) k(c, c) += m.contact_stiffness;
  Eigen::MatrixXd s = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  const Eigen::MatrixXd minv = sys.mass.inverse();
  s.topRightCorner(n, n) = Eigen::MatrixXd::Identity(n, n);
  s.bottomLeftCorner(n, n) = -minv * k;
  s.bottomRightCorner(n, n) = -minv * sys.damping;
  const Eigen::VectorXcd lambda = Eigen::EigenSolver<Eigen::MatrixXd>(s, false).eigenvalues();
  double slowest = std::numeric_limits<double>::infinity();
  for (int i = 0; i < lambda.size(); ++i) slowest = std::min(slowest, -lambda[i].real());
  return std::max(0.0, slowest);
}

Scene frf_rig_scene(const Scene& scene, int pi, double dt) {
  // A 10 m span of an ordinary contact wire: its own dynamics are overwritten every step (the
  // rigid drive), it only carries the contact geometry (eq. 10-13).
  std::ostringstream y;
  y << "name: frf_rig\n"
    << "gravity: " << scene.gravity << "\n"
    << "line: {contact_wire_height: " << scene.contact_wire_height << ", span_length: 10.0, span_count: 1}\n"
    << "contact_wire: {linear_mass: 1.0, bending_stiffness: 100.0, tension: 20000.0}\n"
    << "train: {speed: 0.0, start: 5.0, end: 6.0}\n"
    << "numerics: {element_length: 0.25}\n"
    << "output: {analysis_spans: [0, 1]}\n";
  Scene s = load_scene_string(y.str());
  PantographSpec p = scene.pantographs.at(pi);
  p.position = 0.0;
  p.aero_coefficient = 0.0;
  // The rig is a 2-D line: the strips' widths across the track cannot act there.
  for (CollectorSpec& c : p.collectors) c.working_width.reset();
  for (HeadSpec& h : p.heads)
    for (CollectorSpec& c : h.collectors) c.working_width.reset();
  s.pantographs = {p};
  s.contact = scene.contact;
  if (dt > 0.0) s.numerics.dt = dt;
  validate(s);
  return s;
}

namespace {

// Where the measurement window of one frequency starts and how long it is, in steps: after the
// ramp and the settling of the slowest free mode (sigma, 1/s), in whole periods.
void frf_window(double f, double sigma, double dt, const FrfMeasurement& how, double* t0, long long* start,
                long long* count) {
  const double period = 1.0 / f;
  const double ramp = how.ramp_periods * period;
  const double settle = std::min(how.max_settle_time, sigma > 0.0 ? std::log(1.0 / how.settle_tolerance) / sigma : how.max_settle_time);
  *t0 = ramp + std::ceil(settle / period) * period;
  *start = std::llround(*t0 / dt);
  *count = std::llround(how.window_periods * period / dt);
}

}  // namespace

long long frf_steps(const Model& rig, const std::vector<double>& frequencies, const FrfMeasurement& how) {
  const double sigma = slowest_decay_rate(rig, 0);
  long long total = 0;
  for (double f : frequencies) {
    double t0 = 0.0;
    long long start = 0, count = 0;
    frf_window(f, sigma, rig.dt, how, &t0, &start, &count);
    total += start + count;
  }
  return total;
}

namespace {

// The start of every frequency: the rig's static equilibrium on the still wire, the preloads and
// the uplift against the contact springs (the rig's wire is where the references were set).
// Displacements of the pantograph's DOFs (PantographSystem's order).
Eigen::VectorXd rig_equilibrium(const Model& rig, const PantographSystem& sys) {
  const int pi = 0;
  const Pantograph& p = rig.pantographs.at(pi);
  State s0 = make_state(rig);
  observe(rig, s0);
  Eigen::MatrixXd kc = sys.stiffness;
  Eigen::VectorXd r = preload_force(rig, pi, p.static_uplift);
  const std::size_t nw = rig.contact_wires.size();
  for (std::size_t cj = 0; cj < p.collectors.size(); ++cj) {
    kc(sys.contact[cj], sys.contact[cj]) += rig.contact_stiffness;
    for (std::size_t wk = 0; wk < nw; ++wk) r[sys.contact[cj]] -= s0.contact_force[p.collectors[cj] * nw + wk];
  }
  return kc.ldlt().solve(r);
}

// Drive amplitude (m) at w: the dynamic contact force (analytic, per metre of drive) stays a
// share of the static uplift, so the strips never leave the wire.
double drive_amplitude(const Model& rig, const PantographSystem& sys, double w, const FrfMeasurement& how) {
  Eigen::MatrixXcd a;
  Eigen::VectorXcd b;
  driven_system(rig, sys, w, &a, &b);
  const Eigen::VectorXcd x1 = a.partialPivLu().solve(b);
  std::complex<double> f1 = 0.0;
  for (int c : sys.contact) f1 += rig.contact_stiffness * (x1[c] - 1.0);
  return how.force_share * rig.pantographs.at(0).static_uplift / std::abs(f1);
}

// Moves every contact-wire node as one rigid body: y = Y env(t) sin(w t) with a raised-cosine
// ramp env over `ramp` seconds, and its time derivative as the nodes' velocity.
void drive_rigid_wire(const Model& rig, State& s, double amplitude, double w, double ramp, double t) {
  const double env = t < ramp ? 0.5 * (1.0 - std::cos(kPi * t / ramp)) : 1.0;
  const double denv = t < ramp ? 0.5 * kPi / ramp * std::sin(kPi * t / ramp) : 0.0;
  const double y = amplitude * env * std::sin(w * t);
  const double yd = amplitude * (denv * std::sin(w * t) + env * w * std::cos(w * t));
  for (int wi : rig.contact_wires) {
    const Wire& wire = rig.wires[wi];
    for (int j = 0; j < wire.nodes(); ++j) {
      s.u[wire.w_dof + j] = y;
      s.v[wire.w_dof + j] = yd;
    }
  }
}

// Least squares of the head displacement x and the contact force F on (1, cos, sin) over the
// window: the sums of the normal equations, then x = a + b cos + c sin = Re((b - i c) e^{i w t}).
struct HarmonicFit {
  Eigen::Matrix3d nn = Eigen::Matrix3d::Zero();
  Eigen::Vector3d bx = Eigen::Vector3d::Zero(), bf = Eigen::Vector3d::Zero();
  void add(double w, double t, double head, double force) {
    const Eigen::Vector3d phi(1.0, std::cos(w * t), std::sin(w * t));
    nn += phi * phi.transpose();
    bx += phi * head;
    bf += phi * force;
  }
  std::complex<double> receptance() const {
    const Eigen::Vector3d cx = nn.ldlt().solve(bx), cf = nn.ldlt().solve(bf);
    const std::complex<double> xa(cx[1], -cx[2]), fa(cf[1], -cf[2]);
    return xa / fa;
  }
};

// The head displacement (mean over the collectors' DOFs) and the force on it (+ up: minus the
// contact forces of eq. 22 at the state observed). Throws if a strip has left the wire.
void head_motion(const Model& rig, const PantographSystem& sys, const State& s, double f, double amplitude,
                 double* head_out, double* force_out) {
  const Pantograph& p = rig.pantographs.at(0);
  const std::size_t nw = rig.contact_wires.size();
  double head = 0.0, force = 0.0;
  for (std::size_t cj = 0; cj < p.collectors.size(); ++cj) {
    head += s.u[p.first_dof + sys.contact[cj]];
    for (std::size_t wk = 0; wk < nw; ++wk) {
      const double fc = s.contact_force[p.collectors[cj] * nw + wk];
      if (!(fc > 0.0))
        throw SceneError("pantograph_frf: pantograph '" + p.name + "' lost contact at " + fmt(f) +
                         " Hz (drive amplitude " + fmt(amplitude * 1e3) + " mm); lower the force share");
      force -= fc;  // on the head, + up
    }
  }
  head /= static_cast<double>(p.collectors.size());
  *head_out = head;
  *force_out = force;
}

// One stepped sine at f: from the equilibrium x_eq, ramp, settle and fit over the window.
// `done` (advanced by the steps taken) and `total` count the steps of the whole measurement for
// the progress line.
FrfPoint measure_frequency(const Model& rig, const PantographSystem& sys, const Eigen::VectorXd& x_eq, double f,
                           double sigma, const FrfMeasurement& how, long long* done, long long total) {
  const Pantograph& p = rig.pantographs.at(0);
  const int n = static_cast<int>(sys.mass.rows());
  const double dt = rig.dt, w = 2.0 * kPi * f, period = 1.0 / f;
  const double amplitude = drive_amplitude(rig, sys, w, how);
  const double ramp = how.ramp_periods * period;
  double t0 = 0.0;
  long long start = 0, count = 0;
  frf_window(f, sigma, dt, how, &t0, &start, &count);

  State s = make_state(rig);
  for (int i = 0; i < n; ++i) s.u[p.first_dof + i] = x_eq[i];
  HarmonicFit fit;
  for (long long step_i = 0; step_i < start + count; ++step_i) {
    if (how.progress && (*done + step_i) % how.progress_every == 0) how.progress(*done + step_i, total);
    const double t = step_i * dt;
    drive_rigid_wire(rig, s, amplitude, w, ramp, t);
    observe(rig, s);  // the contact force step() applies over this step (eq. 22 at t_n)
    if (step_i >= start) {
      double head = 0.0, force = 0.0;
      head_motion(rig, sys, s, f, amplitude, &head, &force);
      fit.add(w, t, head, force);
    }
    if (step(rig, s) != StepStatus::kOk)
      throw SceneError("pantograph_frf: the rig run stopped at " + fmt(f) + " Hz, t = " + fmt(t) + " s");
  }
  FrfPoint pt;
  pt.frequency = f;
  pt.receptance = fit.receptance();
  pt.apparent_mass = -1.0 / (w * w * pt.receptance);
  pt.drive_amplitude = amplitude;
  pt.settle_time = t0;
  *done += start + count;
  return pt;
}

}  // namespace

std::vector<FrfPoint> measured_frf(const Model& rig, const std::vector<double>& frequencies, const FrfMeasurement& how) {
  const PantographSystem sys = pantograph_system(rig, 0);
  const double sigma = slowest_decay_rate(rig, 0);
  const Eigen::VectorXd x_eq = rig_equilibrium(rig, sys);
  std::vector<FrfPoint> out;
  const long long total = how.progress ? frf_steps(rig, frequencies, how) : 0;
  long long done = 0;
  for (double f : frequencies) out.push_back(measure_frequency(rig, sys, x_eq, f, sigma, how, &done, total));
  return out;
}

}  // namespace catenary_sim
