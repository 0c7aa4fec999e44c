#include "catenary_sim/core/model/stability.hpp"

#include "util/format.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace catenary_sim {

double highest_eigenfrequency(const Model& m, int iterations, bool explicit_part) {
  int max_nodes = 1;
  for (const Wire& w : m.wires) max_nodes = std::max(max_nodes, w.nodes());
  std::vector<double> scratch(max_nodes);
  const Eigen::VectorXd s = m.inv_mass.cwiseSqrt();  // M^-1/2, 0 on rigid DOFs
  const double front = m.train_start;
  return power_iteration_omega(m.n_dof, s.data(), iterations, [&](const double* x, double* y) {
    apply_stiffness(m, front, x, y, scratch.data(), explicit_part);
  });
}

double critical_time_step(double w, double alpha, double beta) {
  if (w <= 0.0) return 1.0;
  const double xi = alpha / (2.0 * w) + 0.5 * beta * w;
  // sqrt(1 + xi^2) - xi cancels to 0 once xi^2 passes 1/epsilon (a stiff spring on a mass of
  // next to nothing); there its equal 1 / (sqrt(1 + xi^2) + xi) keeps its digits. Below, the
  // difference as written, whose bits every shipped scene's dt has.
  if (xi > 1e4) return (2.0 / w) / (std::sqrt(1.0 + xi * xi) + xi);
  return (2.0 / w) * (std::sqrt(1.0 + xi * xi) - xi);
}

double compute_stability_limit(Model& m, double coupled_omega) {
  // A Rayleigh quotient can only underestimate omega_max; the 0.2 % margin covers what the
  // iteration has not converged (measured: 3e-4 after 400 iterations on the HRZ variant), so the
  // refusal of a user dt is on the safe side.
  // The supports and droppers taken at the step's middle (numerics.supports, numerics.droppers
  // implicit) are left out: with them the step is central differences on the mass M + (dt^2/4) K_I
  // and the stiffness K_E + K_I, stable for dt < 2 / omega_max(K_E, M) whatever K_I
  // (explicit_step.cpp). A slack dropper only takes its K_I away.
  // A coupled frequency is given only where it was found above this model's own (build_model):
  // the plane's own iteration is not run again.
  const double band = coupled_omega > 0.0 ? coupled_omega : 1.002 * highest_eigenfrequency(m, 3000, true);
  m.omega_max = band;
  // The contacts move along the wire: where one meets a light node its frequency is highest, and
  // the power iteration sees it only where the train starts. Add every contact's worst case as a
  // bound (Weyl: lambda_max(A + B) <= lambda_max(A) + lambda_max(B)), with the contact as a
  // rank-1 spring k0 g g^T, g^T M^-1 g <= 1/m_head + max 1/m over the contact-wire nodes.
  double lightest = 0.0;
  for (int wi : m.contact_wires)
    for (int i = 0; i < m.wires[wi].nodes(); ++i) lightest = std::max(lightest, m.inv_mass[m.wires[wi].w_dof + i]);
  double contact = 0.0;
  for (const Collector& c : m.collectors) {
    const Pantograph& p = m.pantographs[c.pantograph];
    if (!p.moving_force) contact += m.contact_stiffness * (m.inv_mass[c.dof] + lightest) * m.contact_wires.size();
  }
  m.omega_max = std::sqrt(m.omega_max * m.omega_max + contact);
  // Centred damping (NumericsSpec::damping) leaves the wires' band the undamped limit; the
  // supports' and droppers' springs keep their explicit share beta k (below).
  const bool centred = m.scene.numerics.damping == DampingStep::kCentred;
  m.dt_critical = centred ? critical_time_step(m.omega_max, 0.0, 0.0) : critical_time_step(m.omega_max, m.alpha, m.beta);
  PointDampingLimit points(m.inv_mass);
  if (centred) {
    const double b = m.beta;
    for (const SupportSpring& sp : m.springs) points.ground(sp.dof, sp.stiffness, b * sp.stiffness);
    for (const Dropper& d : m.droppers) points.link(d.messenger_dof, d.contact_dof, d.stiffness, b * d.stiffness);
    for (const WireClamp& c : m.clamps) points.link(c.upper_dof, c.lower_dof, c.stiffness, b * c.stiffness);
  }
  // The pantographs' dampers are not Rayleigh damping: the half-step velocity of eq. 19-21 takes
  // them explicitly, and a damper c on a light mass m needs dt < 2 m / c even without a spring.
  // With their springs and the contact springs (the wire taken held): far from binding on real
  // pantographs (the reference's lower frame: 33 ms), binding on absurdly light or damped ones,
  // which then get a dt that holds.
  const double wires = static_cast<double>(m.contact_wires.size());
  for (const Pantograph& p : m.pantographs) {
    if (p.moving_force) continue;
    const int n = p.masses_count(), top = p.first_dof;
    for (int i = 0; i + 1 < n; ++i) points.link(top + i, top + i + 1, p.stiffness[i], p.damping[i]);
    points.ground(top + n - 1, p.stiffness[n - 1], p.damping[n - 1]);  // (the last to the roof)
    if (p.heads.empty()) points.ground(top, m.contact_stiffness * static_cast<double>(p.collectors.size()) * wires, 0.0);
    for (const Head& h : p.heads) {
      points.link(top, h.dof, h.stiffness, h.damping);
      points.ground(h.dof, m.contact_stiffness * static_cast<double>(h.collectors.size()) * wires, 0.0);
    }
  }
  m.dt_critical = std::min(m.dt_critical, points.time_step());
  // A mass of next to nothing on a spring (a wire's or pantograph's mass of 1e-200) puts omega_max
  // beyond double precision: no step could follow it, and a NaN here would pass every check below.
  const char* check = "some mass is next to nothing against its stiffness; check the wires' linear_mass and the "
                      "pantographs' masses";
  if (!std::isfinite(m.omega_max))
    throw SceneError("the line's highest natural frequency is beyond double precision (omega_max " + fmt(m.omega_max) +
                     " rad/s): " + check);
  if (!(m.dt_critical > 0.0))
    throw SceneError("the explicit stability limit is not a positive time (" + fmt(m.dt_critical) + " s, omega_max " +
                     fmt(m.omega_max) + " rad/s): " + check);
  return band;
}

}  // namespace catenary_sim
