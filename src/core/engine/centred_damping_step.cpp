// The explicit step with centred damping: the half-step scheme's point forces, the wires' solve
// for zeta per pack (centred_damping.hpp), then the pantographs.
#include "engine/centred_damping_step.hpp"

#include <cmath>

#include "engine/centred_damping.hpp"
#include "engine/forces.hpp"
#include "engine/step_workspace.hpp"
#include "engine/train_motion.hpp"
#include "engine/wire_lanes.hpp"

namespace catenary_sim {

namespace {

// Back to the load the wires' entries add_wire_point_forces and contact_forces wrote (the centred
// step keeps the load in the wires' part of f between steps, its sweep reading load and point
// forces together).
void clear_point_forces(const Model& m, State& s, double* f) {
  const double* load = m.load.data();
  for (const SupportSpring& sp : m.springs) f[sp.dof] = load[sp.dof];
  for (const Dropper& d : m.droppers) {
    f[d.contact_dof] = load[d.contact_dof];
    f[d.messenger_dof] = load[d.messenger_dof];
  }
  for (const WireClamp& c : m.clamps) {
    f[c.stitch_dof] = load[c.stitch_dof];
    f[c.messenger_dof] = load[c.messenger_dof];
  }
  for (const Pantograph& p : m.pantographs)
    for (int ci : p.collectors) {
      const double xc = s.front - p.position + m.collectors[ci].offset;
      for (int wi : m.contact_wires) {
        const Wire& w = m.wires[wi];
        const int cnt = contact_weights(w, m.rub_length, xc, s.work->weight_node.data(), s.work->weight.data());
        for (int a = 0; a < cnt; ++a) f[w.w_dof + s.work->weight_node[a]] = load[w.w_dof + s.work->weight_node[a]];
      }
    }
}

}  // namespace

StepStatus centred_damping_step(const Model& m, State& s) {
  const int n = m.n_dof, nc = m.n_catenary_dof;
  double* u = s.u.data();
  double* v = s.v.data();
  double* f = s.work->force.data();
  double* acc = s.accel.data();
  const double dt = m.dt, beta = m.beta, limit = m.scene.numerics.divergence_limit;
  // The wires' entries of f hold the load here (make_state, clear_point_forces); the point forces
  // are added to it. The supports and droppers read z = u + beta v at their DOFs only.
  auto force_at = [f](int i) -> double& { return f[i]; };
  auto z_at = [u, v, beta](int i) { return u[i] + beta * v[i]; };
  if (leaning(m, s)) add_wire_point_forces<true>(m, s, u, v, force_at, z_at, false);
  else add_wire_point_forces<false>(m, s, u, v, force_at, z_at, false);
  add_pantograph_forces(m, s, u, v, f);
  for (int d : m.wire_packs->centred_fixed_dofs) f[d] = 0.0;  // a fixed node's row is zeta = u (a contact may reach it; load 0)
  double* un = s.work->u_next.data();
  double* vn = s.work->v_next.data();
  bool out = false;
  for (const WireLanes& p : packs_of(m)) out |= centred_sweep_pack(m, p, s);
  clear_point_forces(m, s, f);
  const double* im = m.inv_mass.data();
  for (int i = nc; i < n; ++i) {
    acc[i] = im[i] * f[i];
    vn[i] = v[i] + dt * acc[i];
    un[i] = u[i] + dt * vn[i];
    out |= !(std::fabs(un[i]) <= limit);
  }
  if (out) {
    for (int i = 0; i < n; ++i)
      if (!(std::fabs(un[i]) <= limit)) {
        s.status = StepStatus::kDiverged;
        s.diverged_dof = i;
        break;
      }
    return s.status;
  }
  s.u.swap(s.work->u_next);
  s.v.swap(s.work->v_next);
  advance_train(m, s, dt);
  return s.status;
}

}  // namespace catenary_sim
