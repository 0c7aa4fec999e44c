// The lateral plane's implicit gust lead (lateral_lead.hpp).
#include "engine/lateral_lead.hpp"

#include <algorithm>
#include <cmath>

#include "engine/centred_damping.hpp"
#include "engine/lateral_wind.hpp"
#include "engine/lateral_window.hpp"
#include "engine/lateral_workspace.hpp"
#include "engine/window.hpp"
#include "engine/wire_lanes.hpp"

namespace catenary_sim {

namespace {

// Calls body(i0, i1) on each wire's lead range of lateral DOFs.
template <class Body>
void over_lead(const Model& m, const State& s, Body&& body) {
  const LateralState& ls = s.lateral;
  for (std::size_t wi = 0; wi < m.lateral->wires.size(); ++wi) {
    const WireWindow& ww = ls.lead_window[wi];
    if (ww.hi >= ww.lo) body(m.lateral->wires[wi].w_dof + ww.lo, m.lateral->wires[wi].w_dof + ww.hi + 1);
  }
}

// The wire's impedance sqrt(T rhoA) (N s/m): the cuts' dashpot, as the window's.
double impedance(const Wire& w) { return std::sqrt(w.spec.tension * w.spec.linear_mass); }

// The lead's lists and factors for its placement: the pendulums in it, its cuts' static force, the
// diagonal with the cuts' dashpots c / lead_beta over the shift, the packs' factors.
void rebuild_lead(const Model& m, State& s, double xa, double xb) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  LateralWorkspace& lw = *ls.work;
  auto inside = [&](int dof) { return in_windows(lat.wires, ls.lead_window, dof); };
  lw.lead_dropper_count = select_between(
      m.dropper_order, m.dropper_order_x, xa, xb,
      [&](int k) { return inside(lat.pendulums[k].contact) && inside(lat.pendulums[k].messenger); },
      lw.lead_droppers.data());
  lw.lead_cut_count = lw.lead_extra_count = lw.lead_held_count = lw.lead_dashpot_count = 0;
  double* mass = lw.lead_plane_mass.data();
  const double* im = lat.inv_mass.data();
  for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) {
    const WireWindow& ww = ls.lead_window[wi];
    if (ww.hi < ww.lo) continue;
    const int o = lat.wires[wi].w_dof;
    lw.lead_cut_count = add_cut_forces(m, wi, ww, lw.lead_cut_node.data(), lw.lead_cut_force.data(), lw.lead_cut_count,
                                       lw.lead_f.data(), lw.theta.data());
    for (int i = ww.lo; i <= ww.hi; ++i) mass[o + i] = lat.lead_mass[o + i];
    const double c = impedance(lat.wires[wi]) / lat.lead_beta;
    for (int i : {ww.cut_lo ? o + ww.lo : -1, ww.cut_hi ? o + ww.hi : -1})
      if (i >= 0 && im[i] != 0.0) {
        mass[i] += c / lat.lead_shift;
        lw.lead_dashpot_node[lw.lead_dashpot_count] = i;
        lw.lead_dashpot[lw.lead_dashpot_count++] = c;
      }
    for (int i = o + ww.lo; i <= o + ww.hi; ++i) {
      if (im[i] == 0.0) {
        lw.lead_held[lw.lead_held_count++] = i;
      } else if (mass[i] != lat.mass[i]) {
        lw.lead_extra_node[lw.lead_extra_count] = i;
        lw.lead_extra_diag[lw.lead_extra_count++] = (mass[i] - lat.mass[i]) * lat.lead_shift;
      }
    }
  }
  lw.lead_wind_stale = true;
  const CentredPlane plane{&lat.wires, mass, lat.inv_mass.data(), lat.lead_shift};
  factor_centred_windows(plane, packs_of(m), ls.lead_window, lw.lead_scratch.data(), lw.lead_twin.data(), lw.lead_twin_at,
                         lw.lead_single.data(), lw.lead_single_at);
}

// One lead step of lead_dt (the header's trapezoidal rule). True if a new position left the
// divergence limit: the lead keeps its last good step.
bool lead_step(const Model& m, State& s) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  LateralWorkspace& lw = *ls.work;
  const double dt = lat.lead_dt, bp = lat.lead_beta, ratio = lat.lead_v_ratio;
  const double limit = m.scene.numerics.divergence_limit;
  const double* y = ls.lead_y.data();
  const double* v = ls.lead_v.data();
  double* f = lw.lead_f.data();
  // F: the load and the wind's drag on v_n, the wind at the step's middle.
  const double* load = lat.load.data();
  const double* cw = lat.wind_coefficient.data();
  field_values(m, s).at_time(lat.field, ls.lead_time + 0.5 * dt, lw.lead_points.data());
  if (m.endless) {
    // wind_on_nodes' operations, with each node's place in the field found once while the block,
    // the held points and the lead stand still.
    const WindFieldBuffer& buffer = ls.wind_field;
    if (lw.lead_wind_stale || lw.lead_wind_offset != s.line_offset || lw.lead_wind_first != buffer.first()) {
      const int first = buffer.first(), top = std::max(first, buffer.end() - 2);
      over_lead(m, s, [&](int i0, int i1) {
        for (int i = i0; i < i1; ++i) {
          int j = 0;
          lat.field.locate(lat.node_x[i] + s.line_offset, &j, &lw.lead_wind_weight[i]);
          lw.lead_wind_point[i] = std::clamp(j, first, top) - first;
        }
      });
      lw.lead_wind_stale = false;
      lw.lead_wind_offset = s.line_offset;
      lw.lead_wind_first = first;
    }
    const double U = lat.wind_speed;
    const double* sn = lat.wind_normal.data();
    const double* wp = lw.lead_points.data();
    const int* jp = lw.lead_wind_point.data();
    const double* ap = lw.lead_wind_weight.data();
    over_lead(m, s, [&](int i0, int i1) {
      for (int i = i0; i < i1; ++i) {
        const double vr = (U + (1.0 - ap[i]) * wp[jp[i]] + ap[i] * wp[jp[i] + 1]) * sn[i] - v[i];
        f[i] = load[i] + cw[i] * vr * std::fabs(vr);
      }
    });
  } else {
    double* W = lw.lead_wind.data();
    over_lead(m, s, [&](int i0, int i1) {
      wind_on_nodes(m, s, lw.lead_points.data(), i0, i1, W);
      for (int i = i0; i < i1; ++i) {
        const double vr = W[i] - v[i];
        f[i] = load[i] + cw[i] * vr * std::fabs(vr);
      }
    });
  }
  // A held node's row is zeta = y: f 0. The implicit diagonal's share of D (y + ratio v), which
  // the solve's right-hand side adds with D's, out again; the cuts' dashpot c v_mid =
  // c (zeta - y) / bp is in the solve, so it gives back c y. The cuts' static force of the
  // elements left out.
  const double* im = lat.inv_mass.data();
  for (int j = 0; j < lw.lead_held_count; ++j) f[lw.lead_held[j]] = 0.0;
  for (int j = 0; j < lw.lead_extra_count; ++j) {
    const int i = lw.lead_extra_node[j];
    f[i] -= lw.lead_extra_diag[j] * (y[i] + ratio * v[i]);
  }
  for (int j = 0; j < lw.lead_dashpot_count; ++j) f[lw.lead_dashpot_node[j]] += lw.lead_dashpot[j] * y[lw.lead_dashpot_node[j]];
  for (int j = 0; j < lw.lead_cut_count; ++j)
    if (im[lw.lead_cut_node[j]] != 0.0) f[lw.lead_cut_node[j]] += lw.lead_cut_force[j];
  // The pendulums' coupling at the predicted zeta = y + bp v (their own ends are in the solve).
  for (int j = 0; j < lw.lead_dropper_count; ++j) {
    const LateralPendulum& p = lat.pendulums[lw.lead_droppers[j]];
    const double k = std::max(0.0, m.droppers[p.dropper].static_tension) * p.inv_length;
    if (im[p.contact] != 0.0) f[p.contact] += k * (y[p.messenger] + bp * v[p.messenger]);
    if (im[p.messenger] != 0.0) f[p.messenger] += k * (y[p.contact] + bp * v[p.contact]);
  }
  // Per pack the solve for zeta; its update gives v_{n+1} = (2 / bp) (zeta - y) - v, and
  // y + dt v_{n+1}, which the trapezoidal rule takes as y + dt (v_n + v_{n+1}) / 2.
  const std::vector<WireLanes>& packs = packs_of(m);
  for (std::size_t pk = 0; pk < packs.size(); ++pk) {
    const WireLanes& p = packs[pk];
    const WireWindow& ww = ls.lead_window[p.wire[0]];
    if (ww.hi < ww.lo) continue;
    const CentredArrays plane{y, v, f, lw.lead_y_next.data(), lw.lead_v_next.data(), lw.lead_accel.data()};
    CentredSweep c;
    c.lanes = p.lanes;
    for (int k = 0; k < p.lanes; ++k) c.lane[k] = plane.at(lat.wires[p.wire[k]].w_dof + ww.lo);
    c.nodes = ww.hi - ww.lo + 1;
    c.dt = dt;
    c.v_ratio = ratio;
    c.beta = bp;
    c.limit = 1e300;  // (checked below, on the trapezoidal rule's positions)
    c.twin = lw.lead_twin.data() + lw.lead_twin_at[pk];
    c.single = lw.lead_single.data() + lw.lead_single_at[pk];
    c.record = lw.lead_record.data() + kCentredRecord * p.offset;
    centred_sweep(c);
  }
  double* yn = lw.lead_y_next.data();
  const double* vn = lw.lead_v_next.data();
  int out = 0;
  over_lead(m, s, [&](int i0, int i1) {
    for (int i = i0; i < i1; ++i) {
      yn[i] = y[i] + 0.5 * dt * (v[i] + vn[i]);
      out |= !(std::fabs(yn[i]) <= limit);  // also NaN
    }
  });
  if (out) return true;
  ls.lead_y_before.swap(ls.lead_y);  // O(1): the last step becomes the one before
  ls.lead_v_before.swap(ls.lead_v);
  ls.lead_y.swap(lw.lead_y_next);
  ls.lead_v.swap(lw.lead_v_next);
  ls.lead_time += dt;
  return false;
}

}  // namespace

bool advance_lead(const Model& m, State& s, double t) {
  LateralState& ls = s.lateral;
  const double dt = m.lateral->lead_dt;
  if (ls.work->lead_dirty && ls.lead_first_support >= 0) {  // (a state whose lists were not built here)
    rebuild_lead(m, s, m.support_x[ls.lead_first_support], m.support_x[ls.lead_last_support]);
    ls.work->lead_dirty = false;
  }
  while (ls.lead_time < t - 1e-9 * dt)
    if (lead_step(m, s)) return true;
  return false;
}

void sync_lead(const Model& m, State& s) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  LateralWorkspace& lw = *ls.work;
  const std::vector<double>& sx = m.support_x;
  const int first = ls.window_last_support;
  const int last = first >= 0 ? gust_lead_end(m, s, first) : first;
  if (first == ls.lead_first_support && last == ls.lead_last_support && !lw.lead_dirty) return;
  lw.lead_dirty = false;
  ls.lead_first_support = first;
  ls.lead_last_support = last;
  for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) {
    WireWindow& ww = ls.lead_window[wi];
    const int old_lo = ww.lo, old_hi = ww.hi, o = lat.wires[wi].w_dof;
    if (first >= 0 && last > first) {
      set_wire_window(lat.wires[wi], sx[first], sx[last], ww);
    } else {
      ww.lo = 0;
      ww.hi = -1;
    }
    for (int i = ww.lo; i <= ww.hi; ++i)
      if (i < old_lo || i > old_hi) {
        ls.lead_y[o + i] = ls.lead_y_before[o + i] = lat.initial[o + i];
        ls.lead_v[o + i] = ls.lead_v_before[o + i] = 0.0;
      }
  }
  if (first >= 0) rebuild_lead(m, s, sx[first], sx[last]);
}

void lead_state_at(const Model& m, const State& s, int dof, double t, double* y, double* v) {
  const LateralState& ls = s.lateral;
  const double dt = m.lateral->lead_dt;
  const double w = std::clamp((t - (ls.lead_time - dt)) / dt, 0.0, 1.0);
  *y = ls.lead_y_before[dof] + w * (ls.lead_y[dof] - ls.lead_y_before[dof]);
  *v = ls.lead_v_before[dof] + w * (ls.lead_v[dof] - ls.lead_v_before[dof]);
}

void shift_lead(const Model& m, State& s) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  const int first = ls.lead_first_support - m.endless_shift_spans, last = ls.lead_last_support - m.endless_shift_spans;
  for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) {
    WireWindow& ww = ls.lead_window[wi];
    if (ww.hi < ww.lo) continue;
    const int ns = m.endless_shift_spans * m.span_nodes[wi], o = lat.wires[wi].w_dof;
    for (Eigen::VectorXd* a : {&ls.lead_y, &ls.lead_v, &ls.lead_y_before, &ls.lead_v_before}) {
      double* x = a->data();
      for (int i = std::max(ww.lo, ns); i <= ww.hi; ++i)  // upward: the destination below the source
        if (lat.inv_mass[o + i - ns] > 0.0) x[o + i - ns] = x[o + i];
    }
    const int lo = std::max(0, ww.lo - ns), hi = ww.hi - ns;
    // The same supports a block back (the block's spans are identical): the same node range, its
    // factors at the new nodes.
    if (first >= 0) set_wire_window(lat.wires[wi], m.support_x[first], m.support_x[last], ww);
    for (int i = ww.lo; i <= ww.hi; ++i)
      if (i < lo || i > hi) {
        ls.lead_y[o + i] = ls.lead_y_before[o + i] = lat.initial[o + i];
        ls.lead_v[o + i] = ls.lead_v_before[o + i] = 0.0;
      }
  }
  ls.lead_first_support = ls.lead_last_support = -1;  // sync_lead places it again
  if (first >= 0) {
    ls.lead_first_support = first;
    ls.lead_last_support = last;
    rebuild_lead(m, s, m.support_x[first], m.support_x[last]);
    s.lateral.work->lead_dirty = false;
  }
}

}  // namespace catenary_sim
