// The forces of the explicit and implicit steps (forces.cpp): the constant load, the wires' band
// and Rayleigh damping (eq. 5) through z = u + beta v, and the point forces (supports, droppers,
// pantograph chains, contact) in one fixed order, which the fused sweeps repeat to the bit.
#pragma once

#include <algorithm>
#include <cmath>

#include "catenary_sim/core/model/lateral.hpp"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/engine/state.hpp"

namespace catenary_sim {

// Contact of every collector with every contact wire under it at the state's train position:
// the collector height is the weighted wire height (eq. 12), the force is k0 times the head's
// penetration while compressive (eq. 22, 25), spread on the wire with the same weights.
// Writes state.contact_force and state.collector_height; adds the forces to f unless f is null.
void contact_forces(const Model& m, State& s, const double* u, double* f);

struct StepWorkspace;

// The contact patch of collector `ci` on the `wk`-th contact wire at station xc: the nodes and
// weights of eq. 12-13 (contact_weights), kept in the step's workspace per collector and wire and
// found again only when xc moves. A step needs them at one train position up to four times (the
// nodes it redoes, the heights, the forces, the lateral contact point), and the observation that
// ends a step finds those the next step starts with; their bisections and each element's sine and
// cosine are much of a small model's fixed cost per step. The same numbers, bit for bit.
struct ContactPatch {
  int count = 0;
  const int* node = nullptr;  // wire node indices
  const double* weight = nullptr;
};
ContactPatch contact_patch(const Model& m, StepWorkspace& work, int ci, std::size_t wk, double xc);

// A 3-D line whose state has its lateral plane (make_state gives it one; a state whose lateral
// plane was cleared by hand steps its vertical plane alone, the droppers without a lean).
inline bool leaning(const Model& m, const State& s) { return m.lateral && !s.lateral.dropper_stretch.empty(); }

// kLean (a 3-D line, Model::lateral): every dropper's stretch has its lean's share too, averaged
// over the last lateral step (LateralState::dropper_stretch, lateral.hpp). It is added to the
// elastic stretch of u + beta v undamped: the lean's Rayleigh share beta k dy dy'/l is second
// order in the lateral motion, and the vertical step then reads no lateral velocity. The 2-D
// line (kLean false) does exactly the work it did before. The hinged arms' registrations then
// take the wire's lateral force on their arms' ends (LateralState::registration_force, from the
// last lateral step) last.
template <bool kLean, class ForceAt, class ZAt>
void add_wire_point_forces(const Model& m, State& s, const double* u, const double* v, ForceAt f, ZAt z,
                           bool given_slack) {
  const double* lean = kLean ? s.lateral.dropper_stretch.data() : nullptr;
  // Droppers at the step's middle (numerics.droppers implicit) act after the update (explicit_step.cpp).
  const std::uint8_t* at_middle = m.takes_links_at_middle ? m.dropper_at_middle.data() : nullptr;
  auto dropper = [&](std::size_t k) {
    if (at_middle && at_middle[k]) return;
    // Droppers work only in tension; the switch is decided on the elastic stretch.
    const Dropper& d = m.droppers[k];
    auto z_stretch = [&] {
      double e = z(d.messenger_dof) - z(d.contact_dof);
      if constexpr (kLean) e += lean[k];
      return e;
    };
    if (given_slack) {
      // (The implicit scheme: the lean enters lagged, as an explicit force.)
      if (s.dropper_slack[k]) return;
      const double t = d.static_tension + d.stiffness * z_stretch();
      f(d.contact_dof) += t;
      f(d.messenger_dof) -= t;
      return;
    }
    double stretch = u[d.messenger_dof] - u[d.contact_dof];
    if constexpr (kLean) stretch += lean[k];
    const bool taut = d.static_tension + d.stiffness * stretch > 0.0;
    s.dropper_slack[k] = !taut;
    if (!taut) return;
    const double t = std::max(0.0, d.static_tension + d.stiffness * z_stretch());
    f(d.contact_dof) += t;
    f(d.messenger_dof) -= t;
  };
  // Stitch wires' clamps: bilateral, never slack (at the step's middle, explicit_step.cpp).
  const std::uint8_t* clamp_middle = m.takes_links_at_middle ? m.clamp_at_middle.data() : nullptr;
  auto clamp = [&](std::size_t k) {
    if (clamp_middle && clamp_middle[k]) return;
    const WireClamp& c = m.clamps[k];
    const double t = c.static_force + c.stiffness * (z(c.upper_dof) - z(c.lower_dof));
    f(c.lower_dof) += t;
    f(c.upper_dof) -= t;
  };
  if (m.scene.numerics.windowed()) {
    for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
      const WireWindow& ww = s.window[wi];
      const Wire& w = m.wires[wi];
      // Where the window cuts the wire, a dashpot of the wire's impedance sqrt(T rhoA) lets
      // outgoing waves leave (the exact condition for a taut string).
      const double c = std::sqrt(w.spec.tension * w.spec.linear_mass);
      if (ww.hi >= ww.lo && ww.cut_lo) f(w.w_dof + ww.lo) -= c * v[w.w_dof + ww.lo];
      if (ww.hi >= ww.lo && ww.cut_hi) f(w.w_dof + ww.hi) -= c * v[w.w_dof + ww.hi];
    }
    for (int j = 0; j < s.window_spring_count; ++j) {
      const SupportSpring& sp = m.springs[s.window_springs[j]];
      f(sp.dof) -= sp.stiffness * z(sp.dof);
    }
    for (int j = 0; j < s.window_dropper_count; ++j) dropper(static_cast<std::size_t>(s.window_droppers[j]));
    for (int j = 0; j < s.window_clamp_count; ++j) clamp(static_cast<std::size_t>(s.window_clamps[j]));
  } else {
    for (const SupportSpring& sp : m.springs) f(sp.dof) -= sp.stiffness * z(sp.dof);
    for (std::size_t k = 0; k < m.droppers.size(); ++k) dropper(k);
    for (std::size_t k = 0; k < m.clamps.size(); ++k) clamp(k);
  }
  if constexpr (kLean) {
    const std::vector<LateralRegistration>& regs = m.lateral->registrations;
    const double* arm = s.lateral.registration_force.data();
    const bool windowed = m.scene.numerics.windowed();
    for (std::size_t j = 0; j < regs.size(); ++j) {
      const LateralRegistration& r = regs[j];
      if (windowed && !(r.node >= s.window[r.wire].lo && r.node <= s.window[r.wire].hi)) continue;
      f(r.vertical) += arm[j];
    }
  }
}

// Pantographs: lumped chains (eq. 9), uplift on the lowest mass; then the contact.
void add_pantograph_forces(const Model& m, State& s, const double* u, const double* v, double* f);

// The forces that act on single DOFs, added after the wires' band (assemble_force) in this order:
// the window's dashpots, supports, tension-only droppers (add_wire_point_forces, which reads
// z = u + beta v only at the DOFs of supports and droppers), pantograph chains with their uplift,
// and the contact. With `given_slack` (the implicit scheme) the droppers are not switched here:
// those marked slack in state.dropper_slack carry nothing and the others the linear force of the
// matrix, so that the force and the corrected matrix describe the same active set.
void add_point_forces(const Model& m, State& s, const double* u, const double* v, const double* z, double* f,
                      bool given_slack);

// Total force on every DOF at displacements u and velocities v (eq. 1 right-hand side minus the
// internal and damping forces): constant load, beams, Rayleigh damping (eq. 5) through
// z = u + beta v, then the point forces (add_point_forces). The generic step (rotations as DOFs,
// the implicit scheme); the fused explicit step gives the same bits (explicit_fused_step).
void assemble_force(const Model& m, State& s, const double* u, const double* v, double* z, double* f,
                    bool given_slack = false);

}  // namespace catenary_sim
