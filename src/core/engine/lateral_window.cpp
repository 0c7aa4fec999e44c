// The lateral plane's moving window: which part of each wire the lateral step moves, and the
// forces that stand in for the rest.
#include "engine/lateral_window.hpp"

#include <algorithm>
#include <cmath>

#include "engine/lateral_lead.hpp"
#include "engine/lateral_wind.hpp"
#include "model/centred_factors.hpp"
#include "engine/lateral_workspace.hpp"
#include "engine/window.hpp"
#include "engine/wire_lanes.hpp"

namespace catenary_sim {

int add_cut_forces(const Model& m, std::size_t wi, const WireWindow& ww, int* node, double* force, int count, double* f,
                   double* theta) {
  const LateralModel& lat = *m.lateral;
  const Wire& w = lat.wires[wi];
  const int o = w.w_dof, lo = ww.lo, hi = ww.hi;
  if (hi < lo || (!ww.cut_lo && !ww.cut_hi)) return count;
  for (int i = lo; i <= hi; ++i) f[o + i] = 0.0;
  wire_elastic_force_window(w, ww, lat.initial.data(), f, theta);
  auto add_cut = [&](int i) {
    node[count] = o + i;
    force[count++] = lat.static_elastic_force[o + i] - f[o + i];
  };
  const int lo_end = ww.cut_lo ? std::min(hi, lo + kCutLayer - 1) : lo - 1;
  for (int i = lo; i <= lo_end; ++i) add_cut(i);
  if (ww.cut_hi)
    for (int i = std::max(lo_end + 1, hi - kCutLayer + 1); i <= hi; ++i) add_cut(i);
  return count;
}

namespace {

// One wire's part of the window at stations xa..xb (no window: first < 0): the nodes that left it
// back to the static state at rest, the entering ones' wind, and the static force of the elements
// left out on the cut layers.
void move_wire_window(const Model& m, State& s, std::size_t wi, int first, double xa, double xb, bool turbulent) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  LateralWorkspace& lw = *ls.work;
  double* y = ls.y.data();
  double* v = ls.v.data();
  double* f = lw.f.data();
  const Wire& w = lat.wires[wi];
  WireWindow& ww = ls.window[wi];
  const int o = w.w_dof, old_lo = ww.lo, old_hi = ww.hi;
  if (first >= 0) {
    set_wire_window(w, xa, xb, ww);
  } else {
    ww.lo = 0;
    ww.hi = -1;
  }
  const int lo = ww.lo, hi = ww.hi;
  for (int i = old_lo; i <= old_hi; ++i)
    if (i < lo || i > hi) {
      y[o + i] = lat.initial[o + i];
      v[o + i] = 0.0;
    }
  // The nodes the window reaches in the implicit gust lead take its state now.
  if (lat.lead_every > 0) {
    const WireWindow& lead = ls.lead_window[wi];
    for (int i = std::max(lo, lead.lo); i <= std::min(hi, lead.hi); ++i)
      if (i < old_lo || i > old_hi) lead_state_at(m, s, o + i, s.time - m.dt, &y[o + i], &v[o + i]);
  }
  if (turbulent)
    for (int i = lo; i <= hi; ++i)
      if (i < old_lo || i > old_hi) refresh_wind(m, s, o + i, o + i + 1);
  if (hi < lo) return;
  lw.cut_count = add_cut_forces(m, wi, ww, lw.cut_node.data(), lw.cut_force.data(), lw.cut_count, f, lw.theta.data());
}

// The springs, pendulums (droppers) and stitch wires' clamps between the window's end supports
// whose nodes it holds, and the fused step's nodes with point forces: the cut layers, springs,
// pendulums, clamps, held registrations' rows.
void list_window_points(const Model& m, State& s, int first, double xa, double xb) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  LateralWorkspace& lw = *ls.work;
  auto inside = [&](int dof) { return in_windows(lat.wires, ls.window, dof); };
  lw.window_spring_count = lw.window_dropper_count = lw.window_clamp_count = 0;
  if (first >= 0) {
    lw.window_spring_count = select_between(
        lat.spring_order, lat.spring_order_x, xa, xb, [&](int k) { return inside(lat.springs[k].dof); },
        lw.window_springs.data());
    lw.window_dropper_count = select_between(
        m.dropper_order, m.dropper_order_x, xa, xb,
        [&](int k) { return inside(lat.pendulums[k].contact) && inside(lat.pendulums[k].messenger); },
        lw.window_droppers.data());
    lw.window_clamp_count = select_between(
        m.clamp_order, m.clamp_order_x, xa, xb,
        [&](int k) { return inside(lat.clamps[k].lower) && inside(lat.clamps[k].upper); }, lw.window_clamps.data());
  }
  // The fused step's nodes with point forces: the cut layers, springs, pendulums, clamps, held
  // registrations' rows.
  int q = 0;
  for (int j = 0; j < lw.cut_count; ++j) lw.window_points[q++] = lw.cut_node[j];
  for (int j = 0; j < lw.window_spring_count; ++j) lw.window_points[q++] = lat.springs[lw.window_springs[j]].dof;
  for (int j = 0; j < lw.window_dropper_count; ++j) {
    const LateralPendulum& p = lat.pendulums[lw.window_droppers[j]];
    lw.window_points[q++] = p.contact;
    lw.window_points[q++] = p.messenger;
  }
  for (int j = 0; j < lw.window_clamp_count; ++j) {
    const LateralClamp& c = lat.clamps[lw.window_clamps[j]];
    lw.window_points[q++] = c.lower;
    lw.window_points[q++] = c.upper;
  }
  for (const LateralRegistration& r : lat.registrations) {
    if (r.spring >= 0) continue;
    const WireWindow& ww = ls.window[r.wire];
    int lo = 0, hi = 0;
    registration_reach(r, lat.wires[r.wire].nodes(), &lo, &hi);
    for (int i = std::max(lo, ww.lo); i <= std::min(hi, ww.hi); ++i) lw.window_points[q++] = lat.wires[r.wire].w_dof + i;
  }
  lw.window_point_count = q;
}

// The lateral plane's centred factors of its window (factor_centred_windows).
void factor_centred_window(const Model& m, State& s) {
  const LateralModel& lat = *m.lateral;
  LateralWorkspace& lw = *s.lateral.work;
  const CentredPlane plane{&lat.wires, lat.mass.data(), lat.inv_mass.data(), centred_shift(m, lat.dt)};
  factor_centred_windows(plane, packs_of(m), s.lateral.window, lw.centred_scratch.data(), lw.centred_twin.data(),
                         lw.centred_twin_at, lw.centred_single.data(), lw.centred_single_at);
}

}  // namespace

// The moving window (numerics.window): the lateral plane steps the vertical plane's window
// (State::window, which update_window moved before this step; the lateral waves run at the same
// sqrt(T/rhoA), so the same window holds their echoes) and, in a turbulent wind, a lead of
// LateralModel::gust_lead seconds of travel further ahead, so that a span has felt the gusts that
// long when the pantograph reaches it (unless the lead is stepped on its own: lateral_lead.hpp).
// When it moved, the nodes that left it return to the static state under the mean wind at rest
// (as the vertical plane's to u = 0), the nodes that entered get the wind of the last refresh and
// the implicit lead's state where it holds them (else they are at rest in the static state), and
// the lists are rebuilt: springs, pendulums and clamps in the
// window, and at each cut the static force of the elements left out (-K initial of the whole line
// less the window's), so that the static state stays at rest in the window as outside it. Costs
// what the window holds (bisection for the springs and droppers), not the line.
int gust_lead_end(const Model& m, const State& s, int from) {
  const std::vector<double>& sx = m.support_x;
  const double hi_x = sx[from] + m.lateral->gust_lead * std::fabs(s.speed);  // snapped outward to a support
  const int last = static_cast<int>(std::lower_bound(sx.begin(), sx.end(), hi_x - 1e-6) - sx.begin());
  return std::min(last, static_cast<int>(sx.size()) - 1);
}

void sync_window(const Model& m, State& s) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  LateralWorkspace& lw = *ls.work;
  const std::vector<double>& sx = m.support_x;
  const int first = s.window_first_support;
  int last = s.window_last_support;
  if (first >= 0 && lat.gust_lead > 0.0 && lat.lead_every == 0) last = gust_lead_end(m, s, last);  // (an implicit lead steps on its own)
  if (first == ls.window_first_support && last == ls.window_last_support && !lw.window_dirty) return;
  lw.window_dirty = false;
  ls.window_first_support = first;
  ls.window_last_support = last;
  const bool turbulent = lat.windy && !lat.field.empty();
  lw.cut_count = 0;
  lw.window_fused = !lat.planes.empty();
  const double xa = first >= 0 ? sx[first] : 0.0, xb = first >= 0 ? sx[last] : -1.0;
  for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) {
    const WireWindow& vertical = s.window[wi];
    if (!m.window_holds_sections) move_wire_window(m, s, wi, first, xa, xb, turbulent);
    else if (vertical.hi >= vertical.lo) move_wire_window(m, s, wi, first, lat.wires[wi].x.front(), lat.wires[wi].x.back(), turbulent);
    else move_wire_window(m, s, wi, -1, 0.0, -1.0, turbulent);  // (whole sections: the vertical window's)
  }
  for (const WireLanes& p : packs_of(m))
    if (p.lanes == 2 && (ls.window[p.wire[0]].lo != ls.window[p.wire[1]].lo || ls.window[p.wire[0]].hi != ls.window[p.wire[1]].hi))
      lw.window_fused = false;
  // The window's factors for the substep that reads them (lateral_step): the centred solve's, or
  // the fused sweep's.
  if (!lat.centred_twin.empty()) factor_centred_window(m, s);
  else if (lw.window_fused) interleave_window_factors(packs_of(m), ls.window, lw.sweep_factors.data());
  list_window_points(m, s, first, xa, xb);
}

void add_window_forces(const Model& m, const State& s, const double* v, double* f) {
  const LateralModel& lat = *m.lateral;
  const LateralState& ls = s.lateral;
  const LateralWorkspace& lw = *ls.work;
  for (int j = 0; j < lw.cut_count; ++j) f[lw.cut_node[j]] += lw.cut_force[j];
  for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) {
    const WireWindow& ww = ls.window[wi];
    if (ww.hi < ww.lo) continue;
    const Wire& w = lat.wires[wi];
    const double c = std::sqrt(w.spec.tension * w.spec.linear_mass);
    if (ww.cut_lo) f[w.w_dof + ww.lo] -= c * v[w.w_dof + ww.lo];
    if (ww.cut_hi) f[w.w_dof + ww.hi] -= c * v[w.w_dof + ww.hi];
  }
}

}  // namespace catenary_sim
