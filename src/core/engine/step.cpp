// Explicit central differences with the half-step velocity (paper eq. 19-21, 26):
//   v_{n+1/2} = v_{n-1/2} + dt M^-1 (R_n - K_n q_n - C_n v_{n-1/2} - phi^T lambda_n)
//   q_{n+1}   = q_n + dt v_{n+1/2}
// with C_n = alpha M + beta K_n (eq. 5), droppers switched by their tension every step, and the
// massless collectors condensed: the collector sits on the weighted wire height (eq. 12) and its
// spring k0 carries the contact force (eq. 22) while that force is compressive (eq. 25).
#include <algorithm>
#include <cmath>
#include <limits>

#include "catenary_sim/core/model/newmark_matrix.hpp"
#include "catenary_sim/core/engine/state.hpp"
#include "engine/centred_damping.hpp"
#include "engine/window.hpp"
#include "engine/wire_lanes.hpp"

namespace catenary_sim {

namespace {

// Contact of every collector with every contact wire under it at the state's train position:
// the collector height is the weighted wire height (eq. 12), the force is k0 times the head's
// penetration while compressive (eq. 22, 25), spread on the wire with the same weights.
// Writes state.contact_force and state.collector_height; adds the forces to f unless f is null.
void contact_forces(const Model& m, State& s, const double* u, double* f) {
  const std::size_t nw = m.contact_wires.size();
  for (std::size_t pi = 0; pi < m.pantographs.size(); ++pi) {
    const Pantograph& p = m.pantographs[pi];
    const double uplift = s.uplift[pi] + p.aero_coefficient * air_speed_squared(s, pi);
    const double x_ref = s.front - p.position;
    for (int ci : p.collectors) {
      const Collector& col = m.collectors[ci];
      // The mass this strip sits on: the chain's first mass, or its own head (Section VI).
      const double head = p.moving_force ? 0.0 : p.contact_reference(col) + u[col.dof];
      const double xc = x_ref + col.offset;
      // Collector heights on every contact wire under it (eq. 12).
      double lowest = std::numeric_limits<double>::infinity();
      for (std::size_t wk = 0; wk < nw; ++wk) {
        const Wire& w = m.wires[m.contact_wires[wk]];
        const int cnt = contact_weights(w, m.rub_length, xc, s.weight_node.data(), s.weight.data());
        double yw = 0.0;
        for (int a = 0; a < cnt; ++a) yw += s.weight[a] * (w.height[s.weight_node[a]] + u[w.w_dof + s.weight_node[a]]);
        s.collector_height[ci * nw + wk] = cnt ? yw : std::nan("");
        if (cnt) lowest = std::min(lowest, yw);
      }
      // A force-driven collector (moving force, external rig) pushes the lowest wire(s) under it,
      // shared equally among wires within 1 mm of the lowest (a twin contact wire).
      int sharing = 0;
      if (p.moving_force)
        for (std::size_t wk = 0; wk < nw; ++wk) sharing += s.collector_height[ci * nw + wk] <= lowest + 1e-3;
      const double given = (p.external ? s.external_force[pi] : uplift) / p.collectors.size();
      for (std::size_t wk = 0; wk < nw; ++wk) {
        const std::size_t idx = ci * nw + wk;
        const double yw = s.collector_height[idx];
        double fc = 0.0;
        if (!std::isnan(yw)) {
          if (p.moving_force) fc = yw <= lowest + 1e-3 ? given / sharing : 0.0;
          else fc = std::max(0.0, m.contact_stiffness * (head - yw));  // eq. 22 with eq. 25
        }
        s.contact_force[idx] = fc;
        if (fc == 0.0 || !f) continue;
        const Wire& w = m.wires[m.contact_wires[wk]];
        const int cnt = contact_weights(w, m.rub_length, xc, s.weight_node.data(), s.weight.data());
        if (!p.moving_force) f[col.dof] -= fc;
        for (int a = 0; a < cnt; ++a) f[w.w_dof + s.weight_node[a]] += fc * s.weight[a];
      }
    }
  }
}

}  // namespace

State make_state(const Model& m) {
  State s;
  s.u = Eigen::VectorXd::Zero(m.n_dof);
  s.v = Eigen::VectorXd::Zero(m.n_dof);
  s.force = Eigen::VectorXd::Zero(m.n_dof);
  s.accel = Eigen::VectorXd::Zero(m.n_dof);
  if (m.implicit) {
    s.u_pred = Eigen::VectorXd::Zero(m.n_dof);
    s.v_pred = Eigen::VectorXd::Zero(m.n_dof);
    s.solve_tmp = Eigen::VectorXd::Zero(m.n_dof);
    const std::size_t contacts = m.collectors.size() * m.contact_wires.size();
    const std::size_t slots = std::min<std::size_t>(m.droppers.size(), kSlackDropperCapacity);
    const std::size_t corrections = contacts + slots, stride = m.max_contact_nodes + 1;
    s.contact_solve.assign(contacts * m.n_dof, 0.0);
    s.dropper_solve.assign(slots * m.n_dof, 0.0);
    s.dropper_slot.assign(m.droppers.size(), -1);
    s.slot_dropper.assign(slots, -1);
    s.slot_used.assign(slots, -1);
    s.correction_g_index.assign(corrections * stride, 0);
    s.correction_g_value.assign(corrections * stride, 0.0);
    s.correction_g_count.assign(corrections, 0);
    s.correction_factor.assign(corrections, 0.0);
    s.correction_solve.assign(corrections, nullptr);
    s.correction_small.assign(corrections * corrections + corrections, 0.0);
  }
  s.z = Eigen::VectorXd::Zero(m.n_dof);
  // The centred damping step keeps the load in the wires' force entries (clear_point_forces).
  if (m.scene.numerics.damping == DampingStep::kCentred) s.force.head(m.n_catenary_dof) = m.load.head(m.n_catenary_dof);
  if (!m.wire_packs.empty() || m.scene.numerics.damping == DampingStep::kCentred) {
    s.u_next = Eigen::VectorXd::Zero(m.n_dof);
    s.v_next = Eigen::VectorXd::Zero(m.n_dof);
    s.sweep.assign(kSweepRecord * m.sweep_size, 0.0);
    s.point_node.assign(m.collectors.size() * m.contact_wires.size() * m.max_contact_nodes, 0);
    if (m.scene.numerics.windowed()) {
      s.sweep_factors.assign(2 * m.sweep_size, 0.0);
    }
  }
  int max_nodes = 1;
  for (const Wire& w : m.wires) max_nodes = std::max(max_nodes, w.nodes());
  s.theta.assign(max_nodes, 0.0);
  s.weight_node.assign(m.max_contact_nodes, 0);
  s.weight.assign(m.max_contact_nodes, 0.0);
  s.contact_force.assign(m.collectors.size() * m.contact_wires.size(), 0.0);
  s.collector_height.assign(m.collectors.size() * m.contact_wires.size(), 0.0);
  s.dropper_slack.assign(m.droppers.size(), 0);
  s.window.resize(m.wires.size());
  for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
    s.window[wi].tt_lower.assign(m.wires[wi].nodes(), 0.0);
    s.window[wi].tt_inv_pivot.assign(m.wires[wi].nodes(), 0.0);
  }
  s.window_droppers.assign(m.droppers.size(), 0);
  s.window_springs.assign(m.springs.size(), 0);
  s.uplift.resize(m.pantographs.size());
  for (std::size_t i = 0; i < m.pantographs.size(); ++i) s.uplift[i] = m.pantographs[i].static_uplift;
  s.external_force = s.uplift;
  s.head_wind.assign(m.pantographs.size(), 0.0);
  s.front = m.train_start;
  s.line_offset = m.initial_line_offset;
  s.speed = s.target_speed = m.scene.train_speed;
  return s;
}

void observe(const Model& m, State& s) { contact_forces(m, s, s.u.data(), nullptr); }

void contact_point_motion(const Model& m, const State& s, int pantograph, std::vector<ContactPointMotion>& out) {
  out.clear();
  const Pantograph& p = m.pantographs[pantograph];
  // Called every loop period by the HIL node: scratch kept per thread, allocated once.
  thread_local std::vector<int> node;
  thread_local std::vector<double> weight;
  if (node.size() < static_cast<std::size_t>(m.max_contact_nodes)) {
    node.resize(m.max_contact_nodes);
    weight.resize(m.max_contact_nodes);
  }
  for (int ci : p.collectors) {
    const double xc = s.front - p.position + m.collectors[ci].offset;
    for (std::size_t wk = 0; wk < m.contact_wires.size(); ++wk) {
      const Wire& w = m.wires[m.contact_wires[wk]];
      ContactPointMotion c;
      c.collector = ci;
      c.wire = static_cast<int>(wk);
      c.force = s.contact_force[ci * m.contact_wires.size() + wk];
      const int cnt = contact_weights(w, m.rub_length, xc, node.data(), weight.data());
      c.on_wire = cnt > 0;
      if (c.on_wire) {
        c.height = c.velocity = c.acceleration = 0.0;
        for (int a = 0; a < cnt; ++a) {
          const int d = w.w_dof + node[a];
          c.height += weight[a] * (w.height[node[a]] + s.u[d]);
          // explicit: v_{n+1/2} + dt/2 a_n ~ v(t_{n+1}); Newmark: v is already at t_{n+1}
          c.velocity += weight[a] * (m.implicit ? s.v[d] : s.v[d] + 0.5 * m.dt * s.accel[d]);
          c.acceleration += weight[a] * s.accel[d];
        }
        // Slope of the wire (eq. 12 height) at the collector: the height the moving pantograph
        // meets changes by speed x slope on top of the wire's own motion.
        const double dx = 1e-3;
        double yp = 0.0, ym = 0.0;
        const int np = contact_weights(w, m.rub_length, xc + dx, node.data(), weight.data());
        for (int a = 0; a < np; ++a) yp += weight[a] * (w.height[node[a]] + s.u[w.w_dof + node[a]]);
        const int nm = contact_weights(w, m.rub_length, xc - dx, node.data(), weight.data());
        for (int a = 0; a < nm; ++a) ym += weight[a] * (w.height[node[a]] + s.u[w.w_dof + node[a]]);
        c.path_velocity = (np && nm) ? c.velocity + s.speed * (yp - ym) / (2 * dx) : c.velocity;
      }
      out.push_back(c);
    }
  }
}

double pantograph_position(const Model& m, const State& s, int p) {
  return s.front + s.line_offset - m.pantographs[p].position;
}

double head_height(const Model& m, const State& s, int p) {
  const Pantograph& pg = m.pantographs[p];
  if (pg.moving_force) return std::nan("");
  if (pg.heads.empty()) return pg.reference_height + s.u[pg.first_dof];
  double sum = 0.0;  // several heads: their mean
  for (const Head& h : pg.heads) sum += h.reference_height + s.u[h.dof];
  return sum / static_cast<double>(pg.heads.size());
}

int head_count(const Model& m, int p) {
  const Pantograph& pg = m.pantographs[p];
  if (pg.moving_force) return 0;
  return pg.heads.empty() ? 1 : static_cast<int>(pg.heads.size());
}

double head_height(const Model& m, const State& s, int p, int head) {
  const Pantograph& pg = m.pantographs[p];
  if (pg.moving_force) return std::nan("");
  if (pg.heads.empty()) return pg.reference_height + s.u[pg.first_dof];
  const Head& h = pg.heads[head];
  return h.reference_height + s.u[h.dof];
}

double head_aero_uplift(const Model& m, const State& s, int p, int head) {
  const Pantograph& pg = m.pantographs[p];
  if (pg.moving_force || pg.heads.empty()) return 0.0;
  return pg.heads[head].aero_coefficient * air_speed_squared(s, p);
}

double frame_aero_uplift(const Model& m, const State& s, int p) {
  return m.pantographs[p].aero_coefficient * air_speed_squared(s, p);
}

double total_contact_force(const Model& m, const State& s, int p) {
  double f = 0.0;
  const std::size_t nw = m.contact_wires.size();
  for (int ci : m.pantographs[p].collectors)
    for (std::size_t k = 0; k < nw; ++k) f += s.contact_force[ci * nw + k];
  return f;
}

namespace {

// Train kinematics: toward the commanded speed within the acceleration limit.
double next_speed(const State& s, double dt) {
  const double dv = s.target_speed - s.speed, dvmax = s.max_acceleration * dt;
  return (s.max_acceleration <= 0.0 || std::fabs(dv) <= dvmax) ? s.target_speed : s.speed + std::copysign(dvmax, dv);
}

// The end of every step: the train moves, the clock advances, and the observations are taken on
// the new state (t_{n+1}), so a snapshot is always consistent.
void advance_train(const Model& m, State& s, double dt) {
  s.speed = next_speed(s, dt);
  s.front += s.speed * dt;
  s.time += dt;
  ++s.steps;
  contact_forces(m, s, s.u.data(), nullptr);
}

// A 3-D line whose state has its lateral plane (make_state alone gives none: the vertical plane
// then steps alone, as before the lateral plane acted on it).
bool leaning(const Model& m, const State& s) { return m.lateral && !s.lateral.dropper_stretch.empty(); }

// kLean (a 3-D line, Model::lateral): every dropper's stretch has its lean's share too, averaged
// over the last lateral step (LateralState::dropper_stretch, lateral.hpp). It is added to the
// elastic stretch of u + beta v undamped: the lean's Rayleigh share beta k dy dy'/l is second
// order in the lateral motion, and the vertical step then reads no lateral velocity. The 2-D
// line (kLean false) does exactly the work it did before.
template <bool kLean, class ForceAt, class ZAt>
void add_wire_point_forces(const Model& m, State& s, const double* u, const double* v, ForceAt f, ZAt z,
                           bool given_slack) {
  const double* lean = kLean ? s.lateral.dropper_stretch.data() : nullptr;
  auto dropper = [&](std::size_t k) {
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
  } else {
    for (const SupportSpring& sp : m.springs) f(sp.dof) -= sp.stiffness * z(sp.dof);
    for (std::size_t k = 0; k < m.droppers.size(); ++k) dropper(k);
  }
}

// Pantographs: lumped chains (eq. 9), uplift on the lowest mass; then the contact.
void add_pantograph_forces(const Model& m, State& s, const double* u, const double* v, double* f) {
  for (int i = m.n_catenary_dof; i < m.n_dof; ++i) f[i] = 0.0;
  for (std::size_t pi = 0; pi < m.pantographs.size(); ++pi) {
    const Pantograph& p = m.pantographs[pi];
    const double v2 = air_speed_squared(s, pi);
    const double uplift = s.uplift[pi] + p.aero_coefficient * v2;
    if (!p.moving_force) {
      const int nm = p.masses_count(), a0 = p.first_dof;
      for (int i = 0; i < nm; ++i) {
        const int a = a0 + i;
        const bool roof = i + 1 == nm;
        const double ub = roof ? 0.0 : u[a + 1], vb = roof ? 0.0 : v[a + 1];
        const double c = p.spring_preload[i] + p.stiffness[i] * (ub - u[a]) + p.damping[i] * (vb - v[a]);
        f[a] += c;
        if (!roof) f[a + 1] -= c;
      }
      f[a0 + nm - 1] += uplift;
      // Heads on their suspensions to the top frame mass, each with its own aerodynamic uplift.
      for (const Head& h : p.heads) {
        const double c = h.preload + h.stiffness * (u[a0] - u[h.dof]) + h.damping * (v[a0] - v[h.dof]);
        f[h.dof] += c + h.aero_coefficient * v2;
        f[a0] -= c;
      }
    }
  }
  contact_forces(m, s, u, f);
}

// The forces that act on single DOFs, added after the wires' band (assemble_force) in this order:
// the window's dashpots, supports, tension-only droppers (add_wire_point_forces, which reads
// z = u + beta v only at the DOFs of supports and droppers), pantograph chains with their uplift,
// and the contact. With `given_slack` (the implicit scheme) the droppers are not switched here:
// those marked slack in state.dropper_slack carry nothing and the others the linear force of the
// matrix, so that the force and the corrected matrix describe the same active set.
void add_point_forces(const Model& m, State& s, const double* u, const double* v, const double* z, double* f,
                      bool given_slack) {
  auto force_at = [f](int i) -> double& { return f[i]; };
  auto z_at = [z](int i) { return z[i]; };
  if (leaning(m, s)) add_wire_point_forces<true>(m, s, u, v, force_at, z_at, given_slack);
  else add_wire_point_forces<false>(m, s, u, v, force_at, z_at, given_slack);
  add_pantograph_forces(m, s, u, v, f);
}

// Total force on every DOF at displacements u and velocities v (eq. 1 right-hand side minus the
// internal and damping forces): constant load, beams, Rayleigh damping (eq. 5) through
// z = u + beta v, then the point forces (add_point_forces). The generic step (rotations as DOFs,
// the implicit scheme); the fused explicit step gives the same bits (explicit_fused_step).
void assemble_force(const Model& m, State& s, const double* u, const double* v, double* z, double* f,
                    bool given_slack = false) {
  const int nc = m.n_catenary_dof;
  const double beta = m.beta, alpha = m.alpha;
  const double* load = m.load.data();
  const double* mass = m.mass.data();
  auto init = [&](int i0, int i1) {
    for (int i = i0; i < i1; ++i) {
      z[i] = u[i] + beta * v[i];
      f[i] = load[i] - alpha * mass[i] * v[i];
    }
  };
  if (m.scene.numerics.windowed()) {
    for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
      const WireWindow& ww = s.window[wi];
      const Wire& w = m.wires[wi];
      init(w.w_dof + ww.lo, w.w_dof + ww.hi + 1);
    }
    for (std::size_t wi = 0; wi < m.wires.size(); ++wi) wire_elastic_force_window(m.wires[wi], s.window[wi], z, f, s.theta.data());
  } else {
    init(0, nc);
    for (const Wire& w : m.wires) wire_elastic_force(w, z, f, s.theta.data());
  }
  add_point_forces(m, s, u, v, z, f, given_slack);
}

// The explicit step with the wires packed (Model::wire_packs): one fused sweep pair per pack
// (sweep_pack) computes every wire node's force from the band, load and damping and updates it;
// the few nodes that also carry a point force (supports, droppers, the window's dashpots, the
// contact) are then redone: the point forces are added to the band force the sweep kept, in the
// generic step's order, and the update repeated. Every value is the generic step's to the bit. Writes u_next, v_next, accel; returns the diverged DOF or -1, and
// false in `done` if the packs cannot take this state (a window of under two nodes).
int explicit_fused_update(const Model& m, State& s, bool windowed, bool& done) {
  const double* u = s.u.data();
  const double* v = s.v.data();
  double* un = s.u_next.data();
  double* vn = s.v_next.data();
  double* acc = s.accel.data();
  double* f = s.force.data();
  const double dt = m.dt, beta = m.beta, limit = m.scene.numerics.divergence_limit;
  done = true;
  if (windowed) {
    for (const WireWindow& ww : s.window)
      if (ww.hi == ww.lo) done = false;
    for (const WireLanes& p : m.wire_packs)
      if (p.lanes == 2 && (s.window[p.wire[0]].lo != s.window[p.wire[1]].lo || s.window[p.wire[0]].hi != s.window[p.wire[1]].hi))
        done = false;
    if (!done) return -1;
  }
  bool outside = false;
  // The lateral step's band sweep taken along (step_both_planes): both planes' records then in the
  // joint layout (LateralState::sweep, joint_record_index).
  const bool join = m.lateral && s.lateral.join;
  bool lateral_outside = false;
  for (std::size_t pk = 0; pk < m.wire_packs.size(); ++pk) {
    PackSweep a, b;
    if (!setup_pack_sweep(m.wire_packs[pk], m.wires, windowed ? &s.window : nullptr, s.sweep_factors.data(), s.sweep.data(), u, v,
                          un, vn, acc, a))
      continue;
    a.beta = beta;
    a.dt = dt;
    a.limit = limit;
    if (join && setup_lateral_sweep(m, s, pk, false, b)) {
      bool b_outside = false;
      outside |= sweep_pack_pair(a, b, s.lateral.sweep.data() + 2 * kSweepRecord * m.wire_packs[pk].offset, &b_outside);
      lateral_outside |= b_outside;
    } else {
      outside |= sweep_pack(a);
    }
  }
  if (join) {
    s.lateral.joined = true;
    s.lateral.joined_outside = lateral_outside;
    ++s.lateral.joined_steps;
  }

  // The nodes with point forces: the contact wire's nodes under every collector (contact_forces'
  // weights), listed once per step; and (for_each_point) the window's cut ends, supports and
  // droppers, each DOF in the window by construction of its lists. A node may come more than once.
  int contacts = 0;
  int* contact_node = s.point_node.data();
  for (const Pantograph& p : m.pantographs)
    for (int ci : p.collectors) {
      const double xc = s.front - p.position + m.collectors[ci].offset;
      for (int cw : m.contact_wires) {
        const Wire& w = m.wires[cw];
        // The nodes contact_weights gives weights to (without the weights: no sin, cos).
        int first = 0, last = -1;
        const double x0 = w.x.front(), x1 = w.x.back();
        if (m.rub_length <= 0.0) {
          if (xc >= x0 && xc <= x1) last = (first = w.element_at(xc)) + 1;
        } else {
          const double a = xc - 0.5 * m.rub_length, b = xc + 0.5 * m.rub_length;
          if (!(b <= x0 || a >= x1)) {
            first = w.element_at(a);
            last = w.element_at(b) + 1;
          }
        }
        for (int i = first; i <= last; ++i)
          if (!windowed || (i >= s.window[cw].lo && i <= s.window[cw].hi)) contact_node[contacts++] = w.w_dof + i;
      }
    }
  auto for_each_point = [&](auto&& fn) {
    if (windowed) {
      for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
        const WireWindow& ww = s.window[wi];
        if (ww.hi < ww.lo) continue;
        if (ww.cut_lo) fn(m.wires[wi].w_dof + ww.lo);
        if (ww.cut_hi) fn(m.wires[wi].w_dof + ww.hi);
      }
      for (int j = 0; j < s.window_spring_count; ++j) fn(m.springs[s.window_springs[j]].dof);
      for (int j = 0; j < s.window_dropper_count; ++j) {
        const Dropper& d = m.droppers[s.window_droppers[j]];
        fn(d.contact_dof);
        fn(d.messenger_dof);
      }
    } else {
      for (const SupportSpring& sp : m.springs) fn(sp.dof);
      for (const Dropper& d : m.droppers) {
        fn(d.contact_dof);
        fn(d.messenger_dof);
      }
    }
  };
  // Supports, droppers and the window's dashpots act straight on the band forces the sweep left in
  // its records (where z is too), in the generic step's order; the contact nodes then take their
  // force so far into the force vector, where the pantographs' contact adds to it.
  double* rec = join ? s.lateral.sweep.data() : s.sweep.data();
  const int* f_at = m.dof_sweep_force.data();
  const int* z_at = m.dof_sweep_z.data();
  const int joint = join;
  auto force_at = [rec, f_at, joint](int i) -> double& { return rec[joint_record_index(f_at[i], joint, false)]; };
  auto z_rec = [rec, z_at, joint](int i) { return rec[joint_record_index(z_at[i], joint, false)]; };
  if (leaning(m, s)) add_wire_point_forces<true>(m, s, u, v, force_at, z_rec, false);
  else add_wire_point_forces<false>(m, s, u, v, force_at, z_rec, false);
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
  for_each_point([&](int i) { update(i, force_at(i)); });  // the contact nodes last: theirs has the contact
  for (int q = 0; q < contacts; ++q) update(contact_node[q], f[contact_node[q]]);
  for (int i = m.n_catenary_dof; i < m.n_dof; ++i) update(i, f[i]);
  // The displacement check: the sweeps' flag is only a hint (they saw the nodes before the point
  // forces), so on a flag, or a pantograph or point beyond the limit, every new value is scanned
  // in the generic step's order.
  if (!outside) return -1;
  int bad = -1;
  if (windowed) {
    for (std::size_t wi = 0; wi < m.wires.size(); ++wi)
      for (int i = s.window[wi].lo; i <= s.window[wi].hi; ++i)
        if (beyond(m.wires[wi].w_dof + i)) bad = m.wires[wi].w_dof + i;
    for (int i = m.n_catenary_dof; i < m.n_dof; ++i)
      if (beyond(i)) bad = i;
  } else {
    for (int i = 0; i < m.n_dof; ++i)
      if (beyond(i)) bad = i;
  }
  return bad;
}

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
        const int cnt = contact_weights(w, m.rub_length, xc, s.weight_node.data(), s.weight.data());
        double* y = s.contact_solve.data() + static_cast<std::size_t>(active) * n;
        std::fill(y, y + n, 0.0);
        int* gi = s.correction_g_index.data() + active * stride;
        double* gv = s.correction_g_value.data() + active * stride;
        gi[0] = m.collectors[ci].dof;
        gv[0] = 1.0;
        for (int a = 0; a < cnt; ++a) {
          gi[a + 1] = w.w_dof + s.weight_node[a];
          gv[a + 1] = -s.weight[a];
        }
        s.correction_g_count[active] = cnt + 1;
        s.correction_factor[active] = 0.25 * m.dt * m.dt * m.contact_stiffness;
        for (int a = 0; a <= cnt; ++a)
          if (im[gi[a]] != 0.0) y[gi[a]] += gv[a];
        newmark_solve(*m.implicit, y, s.solve_tmp.data());  // y = A^-1 g
        s.correction_solve[active] = y;
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
  int slot = s.dropper_slot[k];
  if (slot < 0) {
    for (std::size_t j = 0; j < s.slot_dropper.size(); ++j)
      if (s.slot_used[j] < s.steps && (slot < 0 || s.slot_used[j] < s.slot_used[slot])) slot = static_cast<int>(j);
    if (slot < 0) return false;
    if (s.slot_dropper[slot] >= 0) s.dropper_slot[s.slot_dropper[slot]] = -1;
    s.slot_dropper[slot] = k;
    s.dropper_slot[k] = slot;
    double* y = s.dropper_solve.data() + static_cast<std::size_t>(slot) * n;
    std::fill(y, y + n, 0.0);
    if (m.inv_mass[d.messenger_dof] != 0.0) y[d.messenger_dof] = 1.0;
    if (m.inv_mass[d.contact_dof] != 0.0) y[d.contact_dof] = -1.0;
    newmark_solve(*m.implicit, y, s.solve_tmp.data());
  }
  s.slot_used[slot] = s.steps;
  int* gi = s.correction_g_index.data() + index * stride;
  double* gv = s.correction_g_value.data() + index * stride;
  int cnt = 0;
  if (m.inv_mass[d.messenger_dof] != 0.0) {
    gi[cnt] = d.messenger_dof;
    gv[cnt++] = 1.0;
  }
  if (m.inv_mass[d.contact_dof] != 0.0) {
    gi[cnt] = d.contact_dof;
    gv[cnt++] = -1.0;
  }
  s.correction_g_count[index] = cnt;
  s.correction_factor[index] = -(0.25 * m.dt * m.dt + 0.5 * m.dt * m.beta) * d.stiffness;
  s.correction_solve[index] = s.dropper_solve.data() + static_cast<std::size_t>(slot) * n;
  return true;
}

// x = (A + sum_i c_i g_i g_i^T)^-1 b given x = A^-1 b (Woodbury):
//   x -= Y (C^-1 + G^T Y)^-1 G^T x, Y = A^-1 G.
// The small matrix is symmetric but indefinite when droppers are taken out: partial pivoting.
// `stride`: entries reserved per correction's g (Model::max_contact_nodes + 1).
void woodbury(State& s, int count, int n, int stride, double* x) {
  if (count == 0) return;
  double* sm = s.correction_small.data();
  double* rhs = sm + count * count;
  auto g_dot = [&](int i, const double* y) {
    const int* gi = s.correction_g_index.data() + i * stride;
    const double* gv = s.correction_g_value.data() + i * stride;
    double r = 0.0;
    for (int a = 0; a < s.correction_g_count[i]; ++a) r += gv[a] * y[gi[a]];
    return r;
  };
  for (int i = 0; i < count; ++i) {
    rhs[i] = g_dot(i, x);
    for (int j = 0; j < count; ++j) sm[i * count + j] = g_dot(i, s.correction_solve[j]) + (i == j ? 1.0 / s.correction_factor[i] : 0.0);
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
    const double* y = s.correction_solve[j];
    const double cj = rhs[j];
    for (int i = 0; i < n; ++i) x[i] -= y[i] * cj;
  }
}

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
  for (const Pantograph& p : m.pantographs)
    for (int ci : p.collectors) {
      const double xc = s.front - p.position + m.collectors[ci].offset;
      for (int wi : m.contact_wires) {
        const Wire& w = m.wires[wi];
        const int cnt = contact_weights(w, m.rub_length, xc, s.weight_node.data(), s.weight.data());
        for (int a = 0; a < cnt; ++a) f[w.w_dof + s.weight_node[a]] = load[w.w_dof + s.weight_node[a]];
      }
    }
}

// The explicit step with centred damping (centred_damping.hpp): the point forces on z = u + beta v
// as in the half-step scheme, then per wire pack the block-tridiagonal solve for zeta and the
// update (centred_sweep_pack; build_model gives such a model its packs), then the pantographs.
StepStatus centred_damping_step(const Model& m, State& s) {
  const int n = m.n_dof, nc = m.n_catenary_dof;
  double* u = s.u.data();
  double* v = s.v.data();
  double* f = s.force.data();
  double* acc = s.accel.data();
  const double dt = m.dt, beta = m.beta, limit = m.scene.numerics.divergence_limit;
  // The wires' entries of f hold the load here (make_state, clear_point_forces); the point forces
  // are added to it. The supports and droppers read z = u + beta v at their DOFs only.
  auto force_at = [f](int i) -> double& { return f[i]; };
  auto z_at = [u, v, beta](int i) { return u[i] + beta * v[i]; };
  if (leaning(m, s)) add_wire_point_forces<true>(m, s, u, v, force_at, z_at, false);
  else add_wire_point_forces<false>(m, s, u, v, force_at, z_at, false);
  add_pantograph_forces(m, s, u, v, f);
  for (int d : m.centred_fixed_dofs) f[d] = 0.0;  // a fixed node's row is zeta = u (a contact may reach it; load 0)
  double* un = s.u_next.data();
  double* vn = s.v_next.data();
  bool out = false;
  for (const WireLanes& p : m.wire_packs) out |= centred_sweep_pack(m, p, s);
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
  s.u.swap(s.u_next);
  s.v.swap(s.v_next);
  advance_train(m, s, dt);
  return s.status;
}

}  // namespace

StepStatus step(const Model& m, State& s) {
  if (s.status != StepStatus::kOk) return s.status;
  if (s.front + s.line_offset >= m.train_end) {
    s.status = StepStatus::kFinished;
    return s.status;
  }
  const int n = m.n_dof;
  const double dt = m.dt;
  double* u = s.u.data();
  double* v = s.v.data();
  double* f = s.force.data();
  double* z = s.z.data();
  double* acc = s.accel.data();
  const double limit = m.scene.numerics.divergence_limit;
  int bad = -1;
  if (!m.implicit && m.scene.numerics.damping == DampingStep::kCentred) return centred_damping_step(m, s);
  if (!m.implicit) {
    const bool windowed = m.scene.numerics.windowed();
    if (m.endless) shift_endless_block(m, s);
    if (windowed) update_window(m, s);
    if (!m.wire_packs.empty()) {
      bool done = false;
      const int diverged = explicit_fused_update(m, s, windowed, done);
      if (done) {
        if (diverged >= 0) {
          s.status = StepStatus::kDiverged;
          s.diverged_dof = diverged;
          return s.status;
        }
        if (windowed) {
          // Outside the window the new buffers hold nothing current: copy the window back.
          auto commit = [&](int i0, int i1) {
            for (int i = i0; i < i1; ++i) {
              v[i] = s.v_next[i];
              u[i] = s.u_next[i];
            }
          };
          for (std::size_t wi = 0; wi < m.wires.size(); ++wi)
            commit(m.wires[wi].w_dof + s.window[wi].lo, m.wires[wi].w_dof + s.window[wi].hi + 1);
          commit(m.n_catenary_dof, n);
        } else {
          s.u.swap(s.u_next);  // O(1): every DOF has its new value
          s.v.swap(s.v_next);
        }
        advance_train(m, s, dt);
        return s.status;
      }
    }
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
      if (bad >= 0) {
        s.status = StepStatus::kDiverged;
        s.diverged_dof = bad;
        return s.status;
      }
      auto commit = [&](int i0, int i1) {
        for (int i = i0; i < i1; ++i) {
          v[i] = v_new[i];
          u[i] = u_new[i];
        }
      };
      for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
        const WireWindow& ww = s.window[wi];
        commit(m.wires[wi].w_dof + ww.lo, m.wires[wi].w_dof + ww.hi + 1);
      }
      commit(m.n_catenary_dof, n);
      advance_train(m, s, dt);
      return s.status;
    } else {
      update(0, n);
    }
  } else {
    // Newmark average acceleration (beta 1/4, gamma 1/2): predict, then solve
    // (M + dt/2 C + dt^2/4 K) a_{n+1} = F(u~, v~) with A = M + dt/2 C0 + dt^2/4 K0 factorised
    // once (every dropper taut, no contact). What switches enters as rank-1 corrections of A
    // (Woodbury), so A is never refactorised:
    //  - every contact in touch at the prediction adds dt^2/4 k0 g g^T, g = e_head - sum_a w_a e_a
    //    (eq. 12);
    //  - every slack dropper takes its (dt^2/4 + dt/2 beta) k g g^T out again, g = e_m - e_c;
    //    which droppers are slack is an active set: start from the last step's, solve, switch the
    //    droppers whose tension at t_{n+1} disagrees, and solve again (rarely more than once).
    const double b = 0.25, g = 0.5;
    // The equation is written at t_{n+1}: the contact sits where the train is then (evaluating it
    // a step behind would shift it along the wire's slope under the head: a bias of order
    // k0 V dt F / (2T), several newtons at 300 km/h and 1 ms).
    const double front_n = s.front;
    s.front = front_n + next_speed(s, dt) * dt;
    double* up = s.u_pred.data();
    double* vp = s.v_pred.data();
    for (int i = 0; i < n; ++i) {
      up[i] = u[i] + dt * v[i] + dt * dt * (0.5 - b) * acc[i];
      vp[i] = v[i] + dt * (1.0 - g) * acc[i];
    }
    const double* im = m.inv_mass.data();
    double* tmp = s.solve_tmp.data();
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
          s.front = front_n;
          s.active_set_full = true;
          s.status = StepStatus::kDiverged;
          s.diverged_dof = -1;
          return s.status;
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
    double* u_new = z;
    double* v_new = s.solve_tmp.data();
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
  }
  if (bad >= 0) {
    s.status = StepStatus::kDiverged;
    s.diverged_dof = bad;
    return s.status;
  }
  s.v.swap(s.force);  // O(1): swaps the buffers, no copy, no allocation
  s.u.swap(s.z);

  advance_train(m, s, dt);
  return s.status;
}

}  // namespace catenary_sim
