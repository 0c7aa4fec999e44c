// Explicit central differences with the half-step velocity (paper eq. 19-21, 26):
//   v_{n+1/2} = v_{n-1/2} + dt M^-1 (R_n - K_n q_n - C_n v_{n-1/2} - phi^T lambda_n)
//   q_{n+1}   = q_n + dt v_{n+1/2}
// with C_n = alpha M + beta K_n (eq. 5), droppers switched by their tension every step, and the
// massless collectors condensed: the collector sits on the weighted wire height (eq. 12) and its
// spring k0 carries the contact force (eq. 22) while that force is compressive (eq. 25).
#include "engine/explicit_step.hpp"

#include <algorithm>
#include <cmath>

#include "engine/forces.hpp"
#include "engine/lateral_workspace.hpp"
#include "engine/step_workspace.hpp"
#include "engine/train_motion.hpp"
#include "engine/window.hpp"
#include "engine/wire_lanes.hpp"

namespace catenary_sim {

namespace {

// Whether the fused sweeps can take this state: a pack's window has the same range in both lanes
// (and two nodes or more, as every wire's window has: set_wire_window).
bool packs_take_window(const Model& m, const State& s, bool windowed) {
  if (!windowed) return true;
  for (const WireLanes& p : packs_of(m))
    if (p.lanes == 2 && (s.window[p.wire[0]].lo != s.window[p.wire[1]].lo || s.window[p.wire[0]].hi != s.window[p.wire[1]].hi))
      return false;
  return true;
}

// The band sweeps of every pack (sweep_pack), a 3-D line's lateral sweep taken along where it can
// (step_both_planes). Returns the vertical sweeps' divergence hint.
bool sweep_packs(const Model& m, State& s, bool windowed) {
  const double* u = s.u.data();
  const double* v = s.v.data();
  double* un = s.work->u_next.data();
  double* vn = s.work->v_next.data();
  double* acc = s.accel.data();
  const double dt = m.dt, beta = m.beta, limit = m.scene.numerics.divergence_limit;
  bool outside = false;
  // The lateral step's band sweep taken along (step_both_planes): both planes' records then in the
  // joint layout (LateralWorkspace::sweep, WirePacks::dof_joint_force).
  const bool join = m.lateral && s.lateral.work->join;
  bool lateral_outside = false;
  for (std::size_t pk = 0; pk < m.wire_packs->packs.size(); ++pk) {
    PackSweep a, b;
    if (!setup_pack_sweep(m.wire_packs->packs[pk], m.wires, windowed ? &s.window : nullptr, s.work->sweep_factors.data(), s.work->sweep.data(), u, v,
                          un, vn, acc, a))
      continue;
    a.beta = beta;
    a.dt = dt;
    a.limit = limit;
    if (join && setup_lateral_sweep(m, s, pk, false, b)) {
      bool b_outside = false;
      double* joint_record = s.lateral.work->sweep.data() + 2 * kSweepRecord * m.wire_packs->packs[pk].offset;
      outside |= sweep_pack_pair(a, b, joint_record, &b_outside);
      lateral_outside |= b_outside;
    } else {
      outside |= sweep_pack(a);
    }
  }
  if (join) {
    s.lateral.work->joined = true;
    s.lateral.work->joined_outside = lateral_outside;
    ++s.lateral.work->joined_steps;
  }
  return outside;
}

// The nodes with point forces: the contact wire's nodes under every collector (contact_forces'
// patches), listed once per step into StepWorkspace::point_node; returns how many. A node may come
// more than once.
int list_contact_nodes(const Model& m, State& s, bool windowed) {
  int contacts = 0;
  int* contact_node = s.work->point_node.data();
  for (const Pantograph& p : m.pantographs)
    for (int ci : p.collectors) {
      const double xc = s.front - p.position + m.collectors[ci].offset;
      for (std::size_t wk = 0; wk < m.contact_wires.size(); ++wk) {
        const int cw = m.contact_wires[wk];
        const ContactPatch cp = contact_patch(m, *s.work, ci, wk, xc);
        for (int a = 0; a < cp.count; ++a) {
          const int i = cp.node[a];
          if (!windowed || (i >= s.window[cw].lo && i <= s.window[cw].hi)) contact_node[contacts++] = m.wires[cw].w_dof + i;
        }
      }
    }
  return contacts;
}

// numerics.supports / numerics.droppers implicit: the springs at the step's middle (the
// trapezoidal rule), after every DOF's explicit update. A spring's force there is its force at q_n
// plus c a, with c = k (dt^2/4 + beta dt/2) (middle_inertia: the stiffness at
// (q_{n+1} + 2 q_n + q_{n-1}) / 4, the damping beta k at (v_{n+1/2} + v_{n-1/2}) / 2) and a the new
// acceleration (v_{n+1/2} - v_{n-1/2}) / dt of its nodes.
// - A support (steady arm, messenger support): the update took its force at q_n, so m a = F
//   becomes (m + c) a = F on its node: the acceleration divided by 1 + c / m.
// - A dropper or a stitch wire's clamp: the update left it out (add_wire_point_forces), so acc
//   holds its ends' accelerations a0 without it. Its force at the middle is T = T_n + c (a_m - a_l),
//   T_n = T0 + k (z_m - z_l) the explicit step's (z = q_n + beta v_{n-1/2}, the lean's share on a
//   3-D line), a the new accelerations of its upper (messenger) and lower (contact wire, auxiliary,
//   stitch wire) ends, a = a0 -/+ T / m. Solved: T = (T_n + c (a0_m - a0_l)) / (1 + c (1/m_m + 1/m_l)).
//   A dropper works only in tension: where that T is not positive it is slack, carries nothing,
//   and a = a0 is then consistent (its stretch at the middle, T's numerator / k, is not positive).
//   So the switch is decided inside the step on the tension it acts with, a complementarity per
//   dropper with one solution; decided at q_n instead, a dropper at this dt goes taut and slack by
//   turns. A clamp is bilateral.
// No node carries two such corrections (mark_springs_at_middle), so each is closed and the order
// does not matter. Writes the droppers' tensions to State::dropper_tension; returns the highest
// corrected DOF beyond the divergence limit (also NaN), or -1.
int springs_at_middle(const Model& m, State& s, bool windowed, const double* u, const double* v, double* un, double* vn,
                      double* acc) {
  const bool supports = m.takes_supports_at_middle, links = m.takes_links_at_middle;
  if (!supports && !links) return -1;
  const double dt = m.dt, beta = m.beta, limit = m.scene.numerics.divergence_limit;
  const double* im = m.inv_mass.data();
  const double* lean = leaning(m, s) ? s.lateral.dropper_stretch.data() : nullptr;
  int beyond = -1;
  auto redo = [&](int i) {
    vn[i] = v[i] + dt * acc[i];
    un[i] = u[i] + dt * vn[i];
    if (!(std::fabs(un[i]) <= limit)) beyond = std::max(beyond, i);
  };
  auto support = [&](int k) {
    if (!m.support_at_middle[k]) return;
    const int i = m.springs[k].dof;
    acc[i] /= 1.0 + middle_inertia(m, m.springs[k].stiffness) * im[i];
    redo(i);
  };
  // The force at the middle of a link of stiffness k, force t0 at zero stretch and the lean's share
  // `lean_stretch`, from its upper end `a` to its lower end `l`.
  auto middle_force = [&](int a, int l, double k, double t0, double lean_stretch) {
    const double stretch = (u[a] + beta * v[a]) - (u[l] + beta * v[l]) + lean_stretch;
    const double c = middle_inertia(m, k);
    return (t0 + k * stretch + c * (acc[a] - acc[l])) / (1.0 + c * (im[a] + im[l]));
  };
  auto apply = [&](int a, int l, double t) {
    acc[l] += im[l] * t;
    acc[a] -= im[a] * t;
    redo(l);
    redo(a);
  };
  auto dropper = [&](int k) {
    if (!m.dropper_at_middle[k]) return;
    const Dropper& d = m.droppers[k];
    const double t = middle_force(d.messenger_dof, d.contact_dof, d.stiffness, d.static_tension, lean ? lean[k] : 0.0);
    const bool taut = t > 0.0;
    s.dropper_slack[k] = !taut;
    s.dropper_tension[k] = taut ? t : 0.0;
    if (taut) apply(d.messenger_dof, d.contact_dof, t);
  };
  auto clamp = [&](int k) {
    if (!m.clamp_at_middle[k]) return;
    const WireClamp& c = m.clamps[k];
    apply(c.upper_dof, c.lower_dof, middle_force(c.upper_dof, c.lower_dof, c.stiffness, c.static_force, 0.0));
  };
  if (windowed) {
    for (int j = 0; supports && j < s.window_spring_count; ++j) support(s.window_springs[j]);
    for (int j = 0; links && j < s.window_dropper_count; ++j) dropper(s.window_droppers[j]);
    for (int j = 0; links && j < s.window_clamp_count; ++j) clamp(s.window_clamps[j]);
  } else {
    for (std::size_t k = 0; supports && k < m.springs.size(); ++k) support(static_cast<int>(k));
    for (std::size_t k = 0; links && k < m.droppers.size(); ++k) dropper(static_cast<int>(k));
    for (std::size_t k = 0; links && k < m.clamps.size(); ++k) clamp(static_cast<int>(k));
  }
  return beyond;
}

// The explicit step with the wires packed (Model::wire_packs): one fused sweep pair per pack
// (sweep_pack) computes every wire node's force from the band, load and damping and updates it;
// the few nodes that also carry a point force (supports, droppers, the window's dashpots, the
// contact) are then redone: the point forces are added to the band force the sweep kept, in the
// generic step's order, and the update repeated.
// Every value is the generic step's to the bit. Writes u_next, v_next, accel; returns the diverged
// DOF or -1.
int explicit_fused_update(const Model& m, State& s, bool windowed) {
  const double* u = s.u.data();
  const double* v = s.v.data();
  double* un = s.work->u_next.data();
  double* vn = s.work->v_next.data();
  double* acc = s.accel.data();
  double* f = s.work->force.data();
  const double dt = m.dt, limit = m.scene.numerics.divergence_limit;
  bool outside = sweep_packs(m, s, windowed);
  const bool join = m.lateral && s.lateral.work->join;
  const int contacts = list_contact_nodes(m, s, windowed);
  const int* contact_node = s.work->point_node.data();
  // Supports, droppers and the window's dashpots act straight on the band forces the sweep left in
  // its records (where z is too), in the generic step's order; the contact nodes then take their
  // force so far into the force vector, where the pantographs' contact adds to it.
  double* rec = join ? s.lateral.work->sweep.data() : s.work->sweep.data();
  const int* f_at = join ? m.wire_packs->dof_joint_force.data() : m.wire_packs->dof_sweep_force.data();
  auto force_at = [rec, f_at](int i) -> double& { return rec[f_at[i]]; };
  const double beta = m.beta;
  auto z_at = [u, v, beta](int i) { return u[i] + beta * v[i]; };  // (the sweep's z, to the bit)
  if (leaning(m, s)) add_wire_point_forces<true>(m, s, u, v, force_at, z_at, false);
  else add_wire_point_forces<false>(m, s, u, v, force_at, z_at, false);
  for (int q = 0; q < contacts; ++q) f[contact_node[q]] = force_at(contact_node[q]);
  add_pantograph_forces(m, s, u, v, f);
  const double* im = m.inv_mass.data();
  auto beyond = [&](int i) { return !(std::fabs(un[i]) <= limit); };
  auto update = [&](int i, double fi) {
    acc[i] = im[i] * fi;  // q'' at t_n (eq. 20)
    vn[i] = v[i] + dt * acc[i];
    un[i] = u[i] + dt * vn[i];
    outside |= beyond(i);
  };
  for_each_point(m, s, windowed, [&](int i) { update(i, force_at(i)); });  // the contact nodes last: theirs has the contact
  for (int q = 0; q < contacts; ++q) update(contact_node[q], f[contact_node[q]]);
  for (int i = m.n_catenary_dof; i < m.n_dof; ++i) update(i, f[i]);
  outside |= springs_at_middle(m, s, windowed, u, v, un, vn, acc) >= 0;
  // The displacement check: the sweeps' flag is only a hint (they saw the nodes before the point
  // forces), so on a flag, or a pantograph or point beyond the limit, every new value is scanned
  // in the generic step's order.
  return outside ? last_beyond(m, s, windowed) : -1;
}

StepStatus diverged(State& s, int dof, const double* u_new) {
  s.status = StepStatus::kDiverged;
  s.diverged_dof = dof;
  s.diverged_displacement = u_new[dof];
  return s.status;
}

// The fused step's end: the new values swapped in (or copied back in the window) once all are good.
StepStatus fused_step(const Model& m, State& s, bool windowed) {
  const int bad = explicit_fused_update(m, s, windowed);
  if (bad >= 0) return diverged(s, bad, s.work->u_next.data());
  if (windowed) {
    commit_window(m, s, s.work->u_next.data(), s.work->v_next.data());
  } else {
    s.u.swap(s.work->u_next);  // O(1): every DOF has its new value
    s.v.swap(s.work->v_next);
  }
  advance_train(m, s, m.dt);
  return s.status;
}

// The generic step: the whole force (assemble_force), then the update of every DOF stepped.
StepStatus generic_step(const Model& m, State& s, bool windowed) {
  const int n = m.n_dof;
  const double dt = m.dt;
  double* u = s.u.data();
  double* v = s.v.data();
  double* f = s.work->force.data();
  double* z = s.work->z.data();
  double* acc = s.accel.data();
  const double limit = m.scene.numerics.divergence_limit;
  int bad = -1;
  assemble_force(m, s, u, v, z, f);
  // Update (eq. 21, 26); rigid DOFs have inv_mass 0 and stay at rest. The new values go to the
  // workspace first: a displacement beyond the divergence limit (or NaN) stops the run and the
  // state keeps the last good step, so nothing diverged is ever passed on.
  const double* im = m.inv_mass.data();
  double* v_new = f;  // the force is no longer needed
  double* u_new = z;
  auto update = [&](int i0, int i1) {
    for (int i = i0; i < i1; ++i) {
      acc[i] = im[i] * f[i];  // q'' at t_n (eq. 20)
      const double vn = v[i] + dt * acc[i];
      const double un = u[i] + dt * vn;
      if (!(std::fabs(un) <= limit)) bad = i;
      v_new[i] = vn;
      u_new[i] = un;
    }
  };
  if (windowed) {
    // Only the window moves: new values for its DOFs go to the workspace, and are copied back
    // (not swapped: outside the window the buffers hold nothing current) once all are good.
    for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
      const WireWindow& ww = s.window[wi];
      update(m.wires[wi].w_dof + ww.lo, m.wires[wi].w_dof + ww.hi + 1);
    }
    update(m.n_catenary_dof, n);
  } else {
    update(0, n);
  }
  // The springs' corrected nodes moved: the last DOF beyond the limit among the final values.
  const bool middle = m.takes_supports_at_middle || m.takes_links_at_middle;
  if (springs_at_middle(m, s, windowed, u, v, u_new, v_new, acc) >= 0 || (bad >= 0 && middle))
    bad = last_beyond(m, s, windowed, u_new);
  if (bad >= 0) return diverged(s, bad, u_new);
  if (windowed) {
    commit_window(m, s, u_new, v_new);
  } else {
    s.v.swap(s.work->force);  // O(1): swaps the buffers, no copy, no allocation
    s.u.swap(s.work->z);
  }
  advance_train(m, s, dt);
  return s.status;
}

}  // namespace

StepStatus explicit_step(const Model& m, State& s) {
  const bool windowed = m.scene.numerics.windowed();
  if (m.endless) shift_endless_block(m, s);
  if (windowed) update_window(m, s);
  if (m.wire_packs && packs_take_window(m, s, windowed)) return fused_step(m, s, windowed);
  return generic_step(m, s, windowed);
}

}  // namespace catenary_sim
