// Energies of the 3-D line: both planes' kinetic and strain energy less the loads' work, the
// droppers' potential V(e) shared by both planes (model/lateral.hpp) counted once.
#include "catenary_sim/core/engine/lateral_energy.hpp"

#include <algorithm>
#include <vector>

#include "engine/lateral_workspace.hpp"

namespace catenary_sim {

namespace {

// V(e) = S0 e + k e^2 / 2 while taut, S0 + k e > 0; constant (its value at the switch) when slack.
double dropper_potential(const Dropper& d, double e) {
  if (!(d.stiffness > 0.0)) return d.static_tension * e;
  e = std::max(e, -d.static_tension / d.stiffness);
  return d.static_tension * e + 0.5 * d.stiffness * e * e;
}

// The lateral plane's energy without the droppers: kinetic, wires, supports and stitch wires'
// clamps, less the loads.
double lateral_wire_energy(const Model& m, const State& s) {
  const LateralModel& lat = *m.lateral;
  const int n = lat.n;
  Eigen::VectorXd f = Eigen::VectorXd::Zero(n);
  std::vector<double> theta(n);
  const double* y = s.lateral.y.data();
  for (const Wire& w : lat.wires) wire_elastic_force(w, y, f.data(), theta.data());  // f = -K y
  for (const LateralSpring& sp : lat.springs) f[sp.dof] -= sp.stiffness * y[sp.dof];
  for (const LateralClamp& c : lat.clamps) {  // (a stitch wire's clamps: k (y_m - y_s)^2 / 2)
    const double d = c.stiffness * (y[c.upper] - y[c.lower]);
    f[c.lower] += d;
    f[c.upper] -= d;
  }
  double e = 0.0;
  for (int i = 0; i < n; ++i)
    e += 0.5 * lat.mass[i] * s.lateral.v[i] * s.lateral.v[i] * (lat.inv_mass[i] > 0.0) - 0.5 * y[i] * f[i] -
         lat.load[i] * y[i];
  return e;
}

}  // namespace

double lateral_energy(const Model& m, const State& s) {
  double e = lateral_wire_energy(m, s);
  const double* u = s.u.data();
  for (const LateralPendulum& p : m.lateral->pendulums) {
    const Dropper& d = m.droppers[p.dropper];
    const double ez = u[d.messenger_dof] - u[d.contact_dof];
    e += dropper_potential(d, ez + lean_stretch(p, s.lateral.y.data())) - dropper_potential(d, ez);
  }
  // The hinged arms' registrations (LateralRegistration), their arms' ends moved out by T: a
  // spring's energy is k (y - stagger - T)^2 / 2, where the sum above took k (y - stagger)^2 / 2;
  // and the wires' energy above falls by F0 T to first order as the registration moves out with
  // their static pull F0, a force on the arm (F0 T'(u)) that the step leaves to the design statics
  // (the arm's f0 and F_h / (a cos^3 theta0) in k_A): added back.
  const LateralModel& lat = *m.lateral;
  const std::vector<double>& pull0 = s.lateral.work->registration_pull0;
  for (std::size_t j = 0; j < lat.registrations.size(); ++j) {
    const LateralRegistration& r = lat.registrations[j];
    const double travel = s.lateral.registration_travel[j];
    if (r.spring >= 0) {
      const LateralSpring& sp = lat.springs[r.spring];
      e += sp.stiffness * travel * (0.5 * travel - (s.lateral.y[r.dof] - sp.anchor));
    }
    e += pull0[j] * travel;
  }
  return e;
}

double line_energy(const Model& m, const State& s) {
  // The vertical plane: 0.5 v M v + 0.5 u K u - load . u over the wires (rotations as DOFs or
  // condensed) and their supports; the droppers' V(e) with the lean's share when 3-D; the stitch
  // wires' clamps.
  const int nc = m.n_catenary_dof;
  Eigen::VectorXd f = Eigen::VectorXd::Zero(m.n_dof);
  int longest = 1;
  for (const Wire& w : m.wires) longest = std::max(longest, w.nodes());
  std::vector<double> theta(longest);
  const double* u = s.u.data();
  for (const Wire& w : m.wires) wire_elastic_force(w, u, f.data(), theta.data());  // f = -K u
  for (const SupportSpring& sp : m.springs) f[sp.dof] -= sp.stiffness * u[sp.dof];
  double e = 0.0;
  for (int i = 0; i < nc; ++i)
    e += 0.5 * m.mass[i] * s.v[i] * s.v[i] * (m.inv_mass[i] > 0.0) - 0.5 * u[i] * f[i] - m.load[i] * u[i];
  for (std::size_t k = 0; k < m.droppers.size(); ++k) {
    const Dropper& d = m.droppers[k];
    e += dropper_potential(d, u[d.messenger_dof] - u[d.contact_dof]);
  }
  // The stitch wires' clamps: the force static_force + k e on the stitch wire's end, e its stretch
  // from the messenger (forces.hpp), is -dV/du_s of V(e) = static_force e + k e^2 / 2.
  for (const WireClamp& c : m.clamps) {
    const double stretch = u[c.upper_dof] - u[c.lower_dof];
    e += c.static_force * stretch + 0.5 * c.stiffness * stretch * stretch;
  }
  if (m.lateral) e += lateral_energy(m, s);
  return e;
}

}  // namespace catenary_sim
