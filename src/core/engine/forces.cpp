// Force assembly (forces.hpp): the massless collectors condensed, the collector on the weighted
// wire height (eq. 12) and its spring k0 carrying the contact force (eq. 22) while compressive
// (eq. 25); the pantographs as lumped chains (eq. 9).
#include "engine/forces.hpp"

#include <limits>

#include "engine/step_workspace.hpp"
#include "engine/window.hpp"

namespace catenary_sim {

ContactPatch contact_patch(const Model& m, StepWorkspace& work, int ci, std::size_t wk, double xc) {
  const std::size_t idx = static_cast<std::size_t>(ci) * m.contact_wires.size() + wk;
  const std::size_t at = idx * static_cast<std::size_t>(m.max_contact_nodes);
  int* node = work.patch_node.data() + at;
  double* weight = work.patch_weight.data() + at;
  if (!(work.patch_x[idx] == xc)) {
    work.patch_count[idx] = contact_weights(m.wires[m.contact_wires[wk]], m.rub_length, xc, node, weight);
    work.patch_x[idx] = xc;
  }
  return ContactPatch{work.patch_count[idx], node, weight};
}

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
        const ContactPatch cp = contact_patch(m, *s.work, ci, wk, xc);
        double yw = 0.0;
        for (int a = 0; a < cp.count; ++a) yw += cp.weight[a] * (w.height[cp.node[a]] + u[w.w_dof + cp.node[a]]);
        s.collector_height[ci * nw + wk] = cp.count ? yw : std::nan("");
        if (cp.count) lowest = std::min(lowest, yw);
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
        const ContactPatch cp = contact_patch(m, *s.work, ci, wk, xc);
        if (!p.moving_force) f[col.dof] -= fc;
        for (int a = 0; a < cp.count; ++a) f[w.w_dof + cp.node[a]] += fc * cp.weight[a];
      }
    }
  }
}

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

void add_point_forces(const Model& m, State& s, const double* u, const double* v, const double* z, double* f,
                      bool given_slack) {
  auto force_at = [f](int i) -> double& { return f[i]; };
  auto z_at = [z](int i) { return z[i]; };
  if (leaning(m, s)) add_wire_point_forces<true>(m, s, u, v, force_at, z_at, given_slack);
  else add_wire_point_forces<false>(m, s, u, v, force_at, z_at, given_slack);
  add_pantograph_forces(m, s, u, v, f);
}

void assemble_force(const Model& m, State& s, const double* u, const double* v, double* z, double* f,
                    bool given_slack) {
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
    for (std::size_t wi = 0; wi < m.wires.size(); ++wi) wire_elastic_force_window(m.wires[wi], s.window[wi], z, f, s.work->theta.data());
  } else {
    init(0, nc);
    for (const Wire& w : m.wires) wire_elastic_force(w, z, f, s.work->theta.data());
  }
  add_point_forces(m, s, u, v, z, f, given_slack);
}

}  // namespace catenary_sim
