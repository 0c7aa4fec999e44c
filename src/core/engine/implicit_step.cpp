// Newmark average acceleration (beta 1/4, gamma 1/2): predict, then solve
// (M + dt/2 C + dt^2/4 K) a_{n+1} = F(u~, v~) with A = M + dt/2 C0 + dt^2/4 K0 factorised
// once (every dropper taut, no contact). What switches enters as rank-1 corrections of A
// (Woodbury), so A is never refactorised:
//  - every contact in touch at the prediction adds dt^2/4 k0 g g^T, g = e_head - sum_a w_a e_a
//    (eq. 12);
//  - every slack dropper takes its (dt^2/4 + dt/2 beta) k g g^T out again, g = e_m - e_c;
//    which droppers are slack is an active set: start from the last step's, solve, switch the
//    droppers whose tension at t_{n+1} disagrees, and solve again (rarely more than once).
#include "engine/implicit_step.hpp"

#include <algorithm>
#include <cmath>

#include "engine/forces.hpp"
#include "engine/step_workspace.hpp"
#include "engine/train_motion.hpp"
#include "model/newmark_matrix.hpp"

namespace catenary_sim {

namespace {

constexpr double kNewmarkBeta = 0.25, kNewmarkGamma = 0.5;

// Columns for the contacts in touch at the prediction (state.contact_force > 0): their sparse
// g = e_head - sum_a w_a e_a (eq. 12), the factor dt^2/4 k0, and A^-1 g. Returns their count;
// they are corrections 0..count-1.
int contact_corrections(const Model& m, State& s) {
  const int n = m.n_dof, stride = m.max_contact_nodes + 1;
  const std::size_t nw = m.contact_wires.size();
  const double* im = m.inv_mass.data();
  int active = 0;
  for (std::size_t pi = 0; pi < m.pantographs.size(); ++pi) {
    const Pantograph& p = m.pantographs[pi];
    if (p.moving_force) continue;
    for (int ci : p.collectors)
      for (std::size_t wk = 0; wk < nw; ++wk) {
        if (!(s.contact_force[ci * nw + wk] > 0.0)) continue;
        const Wire& w = m.wires[m.contact_wires[wk]];
        const double xc = s.front - p.position + m.collectors[ci].offset;
        const ContactPatch cp = contact_patch(m, *s.work, ci, wk, xc);
        const int cnt = cp.count;
        double* y = s.work->contact_solve.data() + static_cast<std::size_t>(active) * n;
        std::fill(y, y + n, 0.0);
        int* gi = s.work->correction_g_index.data() + active * stride;
        double* gv = s.work->correction_g_value.data() + active * stride;
        gi[0] = m.collectors[ci].dof;
        gv[0] = 1.0;
        for (int a = 0; a < cnt; ++a) {
          gi[a + 1] = w.w_dof + cp.node[a];
          gv[a + 1] = -cp.weight[a];
        }
        s.work->correction_g_count[active] = cnt + 1;
        s.work->correction_factor[active] = 0.25 * m.dt * m.dt * m.contact_stiffness;
        for (int a = 0; a <= cnt; ++a)
          if (im[gi[a]] != 0.0) y[gi[a]] += gv[a];
        newmark_solve(*m.implicit, y, s.work->solve_tmp.data());  // y = A^-1 g
        s.work->correction_solve[active] = y;
        ++active;
      }
  }
  return active;
}

// Correction `index` for slack dropper k: g = e_m - e_c, factor -(dt^2/4 + dt/2 beta) k (its share
// of A taken out), A^-1 g from the cache (solved once when the dropper first slackens; the least
// recently used slot not used in this step is reused). False if every slot is in use this step.
bool slack_dropper_correction(const Model& m, State& s, int k, int index) {
  const int n = m.n_dof, stride = m.max_contact_nodes + 1;
  const Dropper& d = m.droppers[k];
  int slot = s.work->dropper_slot[k];
  if (slot < 0) {
    for (std::size_t j = 0; j < s.work->slot_dropper.size(); ++j)
      if (s.work->slot_used[j] < s.steps && (slot < 0 || s.work->slot_used[j] < s.work->slot_used[slot])) slot = static_cast<int>(j);
    if (slot < 0) return false;
    if (s.work->slot_dropper[slot] >= 0) s.work->dropper_slot[s.work->slot_dropper[slot]] = -1;
    s.work->slot_dropper[slot] = k;
    s.work->dropper_slot[k] = slot;
    double* y = s.work->dropper_solve.data() + static_cast<std::size_t>(slot) * n;
    std::fill(y, y + n, 0.0);
    if (m.inv_mass[d.messenger_dof] != 0.0) y[d.messenger_dof] = 1.0;
    if (m.inv_mass[d.contact_dof] != 0.0) y[d.contact_dof] = -1.0;
    newmark_solve(*m.implicit, y, s.work->solve_tmp.data());
  }
  s.work->slot_used[slot] = s.steps;
  int* gi = s.work->correction_g_index.data() + index * stride;
  double* gv = s.work->correction_g_value.data() + index * stride;
  int cnt = 0;
  if (m.inv_mass[d.messenger_dof] != 0.0) {
    gi[cnt] = d.messenger_dof;
    gv[cnt++] = 1.0;
  }
  if (m.inv_mass[d.contact_dof] != 0.0) {
    gi[cnt] = d.contact_dof;
    gv[cnt++] = -1.0;
  }
  s.work->correction_g_count[index] = cnt;
  s.work->correction_factor[index] = -(0.25 * m.dt * m.dt + 0.5 * m.dt * m.beta) * d.stiffness;
  s.work->correction_solve[index] = s.work->dropper_solve.data() + static_cast<std::size_t>(slot) * n;
  return true;
}

// x = (A + sum_i c_i g_i g_i^T)^-1 b given x = A^-1 b (Woodbury):
//   x -= Y (C^-1 + G^T Y)^-1 G^T x, Y = A^-1 G.
// The small matrix is symmetric but indefinite when droppers are taken out: partial pivoting.
// `stride`: entries reserved per correction's g (Model::max_contact_nodes + 1).
void woodbury(State& s, int count, int n, int stride, double* x) {
  if (count == 0) return;
  double* sm = s.work->correction_small.data();
  double* rhs = sm + count * count;
  auto g_dot = [&](int i, const double* y) {
    const int* gi = s.work->correction_g_index.data() + i * stride;
    const double* gv = s.work->correction_g_value.data() + i * stride;
    double r = 0.0;
    for (int a = 0; a < s.work->correction_g_count[i]; ++a) r += gv[a] * y[gi[a]];
    return r;
  };
  for (int i = 0; i < count; ++i) {
    rhs[i] = g_dot(i, x);
    for (int j = 0; j < count; ++j) sm[i * count + j] = g_dot(i, s.work->correction_solve[j]) + (i == j ? 1.0 / s.work->correction_factor[i] : 0.0);
  }
  for (int k = 0; k < count; ++k) {
    int p = k;
    for (int i = k + 1; i < count; ++i)
      if (std::fabs(sm[i * count + k]) > std::fabs(sm[p * count + k])) p = i;
    if (p != k) {
      for (int j = 0; j < count; ++j) std::swap(sm[k * count + j], sm[p * count + j]);
      std::swap(rhs[k], rhs[p]);
    }
    for (int i = k + 1; i < count; ++i) {
      const double l = sm[i * count + k] / sm[k * count + k];
      for (int j = k; j < count; ++j) sm[i * count + j] -= l * sm[k * count + j];
      rhs[i] -= l * rhs[k];
    }
  }
  for (int i = count - 1; i >= 0; --i) {
    double r = rhs[i];
    for (int j = i + 1; j < count; ++j) r -= sm[i * count + j] * rhs[j];
    rhs[i] = r / sm[i * count + i];
  }
  for (int j = 0; j < count; ++j) {
    const double* y = s.work->correction_solve[j];
    const double cj = rhs[j];
    for (int i = 0; i < n; ++i) x[i] -= y[i] * cj;
  }
}

// The accelerations at t_{n+1} in state.force (f) from the prediction u_pred, v_pred: the force,
// A^-1 of it, the contacts' and slack droppers' corrections, and the active set of slack droppers
// updated until it holds (at most kMaxActiveSetPasses solves). False when more droppers are
// slack than the cache holds.
bool solve_active_set(const Model& m, State& s) {
  const int n = m.n_dof;
  const double dt = m.dt, b = kNewmarkBeta;
  double* f = s.work->force.data();
  double* z = s.work->z.data();
  const double* up = s.work->u_pred.data();
  const double* vp = s.work->v_pred.data();
  const double* im = m.inv_mass.data();
  double* tmp = s.work->solve_tmp.data();
  const double bdt2 = b * dt * dt;
  int contacts = 0;
  for (int iteration = 0;; ++iteration) {
    assemble_force(m, s, up, vp, z, f, true);
    for (int i = 0; i < n; ++i)
      if (im[i] == 0.0) f[i] = 0.0;  // rigid supports (every other DOF has mass: rotations are lumped)
    newmark_solve(*m.implicit, f, tmp);
    if (iteration == 0) contacts = contact_corrections(m, s);  // the same set in every iteration
    int count = contacts;
    for (std::size_t k = 0; k < m.droppers.size(); ++k) {
      if (!s.dropper_slack[k]) continue;
      if (!slack_dropper_correction(m, s, static_cast<int>(k), count)) {
        return false;
      }
      ++count;
    }
    woodbury(s, count, n, m.max_contact_nodes + 1, f);
    // The droppers' elastic tension at t_{n+1} decides the set (as in the explicit scheme).
    bool changed = false;
    const double* lean = leaning(m, s) ? s.lateral.dropper_stretch.data() : nullptr;
    for (std::size_t k = 0; k < m.droppers.size(); ++k) {
      const Dropper& d = m.droppers[k];
      double stretch = up[d.messenger_dof] + bdt2 * f[d.messenger_dof] - up[d.contact_dof] - bdt2 * f[d.contact_dof];
      if (lean) stretch += lean[k];  // (lagged, lateral.hpp)
      const std::uint8_t slack = !(d.static_tension + d.stiffness * stretch > 0.0);
      if (slack != s.dropper_slack[k]) {
        s.dropper_slack[k] = slack;
        changed = true;
      }
    }
    // A dropper at the switching point can alternate; after a few passes the last solve stands
    // (its set differs from the exact one by droppers carrying next to no tension).
    if (!changed || iteration == kMaxActiveSetPasses - 1) break;
  }
  return true;
}

}  // namespace

StepStatus implicit_step(const Model& m, State& s) {
  const int n = m.n_dof;
  const double dt = m.dt;
  double* u = s.u.data();
  double* v = s.v.data();
  double* f = s.work->force.data();
  double* z = s.work->z.data();
  double* acc = s.accel.data();
  const double limit = m.scene.numerics.divergence_limit;
  int bad = -1;
  const double b = kNewmarkBeta, g = kNewmarkGamma;
  // The equation is written at t_{n+1}: the contact sits where the train is then (evaluating it
  // a step behind would shift it along the wire's slope under the head: a bias of order
  // k0 V dt F / (2T), several newtons at 300 km/h and 1 ms).
  const double front_n = s.front;
  s.front = front_n + next_speed(s, dt) * dt;
  double* up = s.work->u_pred.data();
  double* vp = s.work->v_pred.data();
  for (int i = 0; i < n; ++i) {
    up[i] = u[i] + dt * v[i] + dt * dt * (0.5 - b) * acc[i];
    vp[i] = v[i] + dt * (1.0 - g) * acc[i];
  }
  if (!solve_active_set(m, s)) {
    s.front = front_n;
    s.active_set_full = true;
    s.status = StepStatus::kDiverged;
    s.diverged_dof = -1;
    return s.status;
  }
  double* u_new = z;
  double* v_new = s.work->solve_tmp.data();
  for (int i = 0; i < n; ++i) {
    const double un = up[i] + b * dt * dt * f[i];
    if (!(std::fabs(un) <= limit)) bad = i;
    u_new[i] = un;
    v_new[i] = vp[i] + g * dt * f[i];
  }
  if (bad < 0) {
    for (int i = 0; i < n; ++i) acc[i] = f[i];
    std::copy(v_new, v_new + n, f);  // f becomes the new velocity, swapped in below
  }
  s.front = front_n;  // the kinematics below advance it once
  if (bad >= 0) {
    s.status = StepStatus::kDiverged;
    s.diverged_dof = bad;
    s.diverged_displacement = u_new[bad];
    return s.status;
  }
  s.v.swap(s.work->force);  // O(1): swaps the buffers, no copy, no allocation
  s.u.swap(s.work->z);
  advance_train(m, s, dt);
  return s.status;
}

}  // namespace catenary_sim
