// The explicit step with centred damping: the half-step scheme's point forces, the wires' solve
// for zeta per pack (centred_damping.hpp), then the pantographs.
#include "engine/centred_damping_step.hpp"

#include <cmath>

#include "engine/centred_damping.hpp"
#include "catenary_sim/core/engine/lateral_step.hpp"
#include "engine/forces.hpp"
#include "engine/lateral_workspace.hpp"
#include "engine/step_workspace.hpp"
#include "engine/train_motion.hpp"
#include "engine/window.hpp"
#include "engine/wire_lanes.hpp"

namespace catenary_sim {

namespace {

// Back to the load the wires' entries add_wire_point_forces and contact_forces wrote (the centred
// step keeps the load in the wires' part of f between steps, its sweep reading load and point
// forces together).
void clear_point_forces(const Model& m, State& s, bool windowed, double* f) {
  const double* load = m.load.data();
  for_each_point(m, s, windowed, [f, load](int i) { f[i] = load[i]; });
  for (const Pantograph& p : m.pantographs)
    for (int ci : p.collectors) {
      const double xc = s.front - p.position + m.collectors[ci].offset;
      for (std::size_t wk = 0; wk < m.contact_wires.size(); ++wk) {
        const Wire& w = m.wires[m.contact_wires[wk]];
        const ContactPatch cp = contact_patch(m, *s.work, ci, wk, xc);
        for (int a = 0; a < cp.count; ++a) f[w.w_dof + cp.node[a]] = load[w.w_dof + cp.node[a]];
      }
    }
}

// Each pack's solve over the window's node range (both lanes share it), with the window's factors.
bool sweep_window(const Model& m, State& s) {
  const StepWorkspace& w = *s.work;
  const std::vector<WireLanes>& packs = packs_of(m);
  bool out = false;
  for (std::size_t pk = 0; pk < packs.size(); ++pk) {
    const WireWindow& ww = s.window[packs[pk].wire[0]];
    if (ww.hi < ww.lo) continue;
    out |= centred_sweep_pack(m, packs[pk], s, ww.lo, ww.hi, w.centred_twin.data() + w.centred_twin_at[pk],
                              w.centred_single.data() + w.centred_single_at[pk]);
  }
  return out;
}

// Each pack's solve over its whole wires; a lone wire's lateral plane taken along in a second lane
// where the lateral step set its forces for it (take_centred_solve_along), that plane's
// divergence hint left for lateral_step. Returns the vertical plane's.
bool sweep_packs(const Model& m, State& s) {
  const std::vector<WireLanes>& packs = packs_of(m);
  const bool join = m.lateral && s.lateral.work->join;
  bool out = false, lateral_out = false;
  for (std::size_t pk = 0; pk < packs.size(); ++pk) {
    if (join && joins_centred(m, pk)) {
      const int beyond = centred_sweep_both_planes(m, pk, s);
      out |= (beyond & 1) != 0;
      lateral_out |= (beyond & 2) != 0;
    } else {
      out |= centred_sweep_pack(m, packs[pk], s);
    }
  }
  if (join) {
    LateralWorkspace& lw = *s.lateral.work;
    lw.joined = true;
    lw.joined_outside = lateral_out;
    ++lw.joined_steps;
  }
  return out;
}

}  // namespace

StepStatus centred_damping_step(const Model& m, State& s) {
  const bool windowed = m.scene.numerics.windowed();
  if (m.endless) shift_endless_block(m, s);
  if (windowed) update_window(m, s);
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
  if (windowed) out = sweep_window(m, s);
  else out = sweep_packs(m, s);
  clear_point_forces(m, s, windowed, f);
  const double* im = m.inv_mass.data();
  for (int i = nc; i < n; ++i) {
    acc[i] = im[i] * f[i];
    vn[i] = v[i] + dt * acc[i];
    un[i] = u[i] + dt * vn[i];
    out |= !(std::fabs(un[i]) <= limit);
  }
  if (out) {
    s.status = StepStatus::kDiverged;
    if (windowed) {
      s.diverged_dof = last_beyond(m, s, true);
    } else {
      for (int i = 0; i < n; ++i)
        if (!(std::fabs(un[i]) <= limit)) {
          s.diverged_dof = i;
          break;
        }
    }
    if (s.diverged_dof >= 0) s.diverged_displacement = un[s.diverged_dof];
    return s.status;
  }
  if (windowed) {
    commit_window(m, s, un, vn);  // (outside the window the new buffers hold nothing current)
  } else {
    s.u.swap(s.work->u_next);
    s.v.swap(s.work->v_next);
  }
  advance_train(m, s, dt);
  return s.status;
}

}  // namespace catenary_sim
