// The state of a pass: made once, sized for the model (step() never allocates), and observed.
#include "catenary_sim/core/engine/state.hpp"

#include <algorithm>
#include <cmath>

#include "engine/forces.hpp"
#include "model/centred_factors.hpp"
#include "engine/step_workspace.hpp"
#include "engine/wire_lanes.hpp"
#include "util/deep_copied_impl.hpp"

namespace catenary_sim {

template class DeepCopied<StepWorkspace>;  // StepWorkspaceHandle

State make_state(const Model& m) {
  State s;
  s.u = Eigen::VectorXd::Zero(m.n_dof);
  s.v = Eigen::VectorXd::Zero(m.n_dof);
  s.work->force = Eigen::VectorXd::Zero(m.n_dof);
  s.accel = Eigen::VectorXd::Zero(m.n_dof);
  if (m.implicit) {
    s.work->u_pred = Eigen::VectorXd::Zero(m.n_dof);
    s.work->v_pred = Eigen::VectorXd::Zero(m.n_dof);
    s.work->solve_tmp = Eigen::VectorXd::Zero(m.n_dof);
    const std::size_t contacts = m.collectors.size() * m.contact_wires.size();
    const std::size_t slots = std::min<std::size_t>(m.droppers.size(), kSlackDropperCapacity);
    const std::size_t corrections = contacts + slots, stride = m.max_contact_nodes + 1;
    s.work->contact_solve.assign(contacts * m.n_dof, 0.0);
    s.work->dropper_solve.assign(slots * m.n_dof, 0.0);
    s.work->dropper_slot.assign(m.droppers.size(), -1);
    s.work->slot_dropper.assign(slots, -1);
    s.work->slot_used.assign(slots, -1);
    s.work->correction_g_index.assign(corrections * stride, 0);
    s.work->correction_g_value.assign(corrections * stride, 0.0);
    s.work->correction_g_count.assign(corrections, 0);
    s.work->correction_factor.assign(corrections, 0.0);
    s.work->correction_solve.assign(corrections, nullptr);
    s.work->correction_small.assign(corrections * corrections + corrections, 0.0);
  }
  s.work->z = Eigen::VectorXd::Zero(m.n_dof);
  // The centred damping step keeps the load in the wires' force entries (clear_point_forces).
  if (m.scene.numerics.damping == DampingStep::kCentred) s.work->force.head(m.n_catenary_dof) = m.load.head(m.n_catenary_dof);
  if (m.wire_packs || m.scene.numerics.damping == DampingStep::kCentred) {
    s.work->u_next = Eigen::VectorXd::Zero(m.n_dof);
    s.work->v_next = Eigen::VectorXd::Zero(m.n_dof);
    s.work->sweep.assign(kCentredRecord * sweep_size(m), 0.0);
    s.work->point_node.assign(m.collectors.size() * m.contact_wires.size() * m.max_contact_nodes, 0);
    if (m.scene.numerics.windowed() && m.scene.numerics.damping != DampingStep::kCentred) {
      s.work->sweep_factors.assign(2 * sweep_size(m), 0.0);  // (the half-step sweep's window factors)
    }
  }
  int max_nodes = 1;
  for (const Wire& w : m.wires) max_nodes = std::max(max_nodes, w.nodes());
  if (m.scene.numerics.windowed() && m.scene.numerics.damping == DampingStep::kCentred) {
    // A window's range has at most its wires' nodes: the whole wires' layout sizes it.
    std::size_t twin = 0, single = 0;
    for (const WireLanes& p : packs_of(m)) {
      s.work->centred_twin_at.push_back(twin);
      s.work->centred_single_at.push_back(single);
      twin += p.centred_twin.size();
      single += p.centred_single.size();
    }
    s.work->centred_twin.assign(twin, 0.0);
    s.work->centred_single.assign(single, 0.0);
    s.work->centred_scratch.assign(static_cast<std::size_t>(max_nodes) * kCdValues, 0.0);
  }
  s.work->theta.assign(max_nodes, 0.0);
  const std::size_t patches = m.collectors.size() * m.contact_wires.size();
  s.work->patch_x.assign(patches, std::nan(""));
  s.work->patch_count.assign(patches, 0);
  s.work->patch_node.assign(patches * m.max_contact_nodes, 0);
  s.work->patch_weight.assign(patches * m.max_contact_nodes, 0.0);
  s.contact_force.assign(m.collectors.size() * m.contact_wires.size(), 0.0);
  s.collector_height.assign(m.collectors.size() * m.contact_wires.size(), 0.0);
  s.dropper_slack.assign(m.droppers.size(), 0);
  if (m.takes_links_at_middle) s.dropper_tension.assign(m.droppers.size(), std::nan(""));
  s.window.resize(m.wires.size());
  for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
    s.window[wi].tt_lower.assign(m.wires[wi].nodes(), 0.0);
    s.window[wi].tt_inv_pivot.assign(m.wires[wi].nodes(), 0.0);
    if (m.wires[wi].twisted && m.scene.numerics.windowed()) {  // stations up to a window's meeting: at most half the wire's nodes, and one
      const std::size_t stations = static_cast<std::size_t>(m.wires[wi].nodes()) / 2 + 1;
      s.window[wi].twisted_lower.assign(stations, 0.0);
      s.window[wi].twisted_inv_pivot.assign(stations, 0.0);
      s.window[wi].twisted_coef.assign(stations * WireLanes::kCoefficients * 2, 0.0);
      s.window[wi].twisted_factors.assign(stations * 2 * 2, 0.0);
    }
  }
  s.window_droppers.assign(m.droppers.size(), 0);
  s.window_springs.assign(m.springs.size(), 0);
  s.window_clamps.assign(m.clamps.size(), 0);
  s.uplift.resize(m.pantographs.size());
  for (std::size_t i = 0; i < m.pantographs.size(); ++i) s.uplift[i] = m.pantographs[i].static_uplift;
  s.external_force = s.uplift;
  s.head_wind.assign(m.pantographs.size(), 0.0);
  s.front = m.train_start;
  s.line_offset = m.initial_line_offset;
  s.speed = s.target_speed = m.scene.train_speed;
  if (m.lateral) s.lateral = make_lateral_state(m);  // a 3-D line: step() moves both planes
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

}  // namespace catenary_sim
