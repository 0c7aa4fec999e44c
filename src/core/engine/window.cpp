// The moving window (numerics.window): only the spans around the pantographs are integrated.
// Ahead of it the line is at its static state, which is u = 0 (the dynamics run on displacements
// from the design state), so spans join it at static equilibrium for free; behind it they leave
// and return to that state. The window moves a whole span at a time (its ends on supports), so
// the band and the condensation factors of the window change only then.
#include "engine/window.hpp"

#include <algorithm>
#include <cmath>

#include "catenary_sim/core/model/beam.hpp"
#include "catenary_sim/core/model/lateral.hpp"
#include "engine/step_workspace.hpp"
#include "model/centred_factors.hpp"
#include "model/twisted_half.hpp"
#include "model/wire_packs.hpp"

namespace catenary_sim {

void shift_endless_block(const Model& m, State& s) {
  const int spans = m.endless_shift_spans;
  const double span = spans * m.endless_span;
  if (!(s.front + m.rear_collector_offset >= m.endless_home + span)) return;
  double* u = s.u.data();
  double* v = s.v.data();
  double* a = s.accel.data();
  // A stitched line's stitch wires: the whole wire handed over, or back to u = 0 at rest.
  hand_over_clamped_wires(
      m, s.window,
      [&](int to, int from, const WireWindow&) {
        const int w0 = m.wires[to].w_dof, src = m.wires[from].w_dof;
        for (int i = 0; i < m.wires[to].nodes(); ++i) {
          u[w0 + i] = u[src + i];
          v[w0 + i] = v[src + i];
          a[w0 + i] = a[src + i];
        }
      },
      [&](int wire, const WireWindow&) {
        const int w0 = m.wires[wire].w_dof;
        for (int i = 0; i < m.wires[wire].nodes(); ++i) u[w0 + i] = v[w0 + i] = a[w0 + i] = 0.0;
      });
  for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
    WireWindow& ww = s.window[wi];
    if (ww.hi < ww.lo || m.wires[wi].is_clamped_wire) continue;
    const int ns = spans * m.span_nodes[wi], w0 = m.wires[wi].w_dof;
    for (int i = ww.lo; i <= ww.hi; ++i) {  // upward: the destination is always below the source
      u[w0 + i - ns] = u[w0 + i];
      v[w0 + i - ns] = v[w0 + i];
      a[w0 + i - ns] = a[w0 + i];
    }
    for (int i = std::max(ww.lo, ww.hi - ns + 1); i <= ww.hi; ++i) u[w0 + i] = v[w0 + i] = a[w0 + i] = 0.0;
    ww.lo -= ns;
    ww.hi -= ns;
  }
  if (m.lateral) shift_lateral_block(m, s);
  s.front -= span;
  s.line_offset += span;
  // The window now spans one support less on both ends; update_window() rebuilds its factors and
  // lists there (the node ranges already match, so nothing is reset).
  s.window_first_support = s.window_last_support = -1;
}

void set_wire_window(const Wire& w, double a, double b, WireWindow& ww) {
  const int n = w.nodes();
  ww.meet = -1;
  ww.lo = static_cast<int>(std::lower_bound(w.x.begin(), w.x.end(), a - 1e-9) - w.x.begin());
  ww.hi = static_cast<int>(std::upper_bound(w.x.begin(), w.x.end(), b + 1e-9) - w.x.begin()) - 1;
  // A wire whose end node alone lies in the window (a section starting at its front support) has
  // no element there: nothing in the window acts on that node, and its rotation's pivot would be
  // 0. It takes part once the window holds an element of it.
  if (ww.hi == ww.lo) ww.hi = ww.lo - 1;
  if (ww.hi < ww.lo) return;
  ww.cut_lo = ww.lo > 0;
  ww.cut_hi = ww.hi < n - 1;
  ww.lo_ww = ww.lo_wt = ww.lo_tt = ww.hi_ww = ww.hi_wt = ww.hi_tt = 0.0;
  if (ww.cut_lo) {
    const Matrix4 k = beam_stiffness(w.x[ww.lo] - w.x[ww.lo - 1], w.spec.bending_stiffness, w.spec.tension);
    ww.lo_ww = k[2][2];
    ww.lo_wt = k[2][3];
    ww.lo_tt = k[3][3];
  }
  if (ww.cut_hi) {
    const Matrix4 k = beam_stiffness(w.x[ww.hi + 1] - w.x[ww.hi], w.spec.bending_stiffness, w.spec.tension);
    ww.hi_ww = k[0][0];
    ww.hi_wt = k[0][1];
    ww.hi_tt = k[1][1];
  }
  // LDL^T of the window's tridiagonal K_theta_theta (free rotations at the cut ends).
  double d = 0.0;
  for (int i = ww.lo; i <= ww.hi; ++i) {
    double diag = w.d_tt[i];
    if (i == ww.lo) diag -= ww.lo_tt;
    if (i == ww.hi) diag -= ww.hi_tt;
    if (i == ww.lo) {
      d = diag;
      ww.tt_lower[i] = 0.0;
    } else {
      const double l = w.e_tt[i - 1] / d;
      d = diag - l * w.e_tt[i - 1];
      ww.tt_lower[i] = l;
    }
    ww.tt_inv_pivot[i] = 1.0 / d;
  }
  // A wire swept from both ends (Wire::twisted), over an odd count of nodes: the mirrored half's
  // factors from hi, meeting in the middle.
  if (w.twisted && (ww.hi - ww.lo) % 2 == 0 && ww.hi - ww.lo >= 2) {
    ww.meet = (ww.hi - ww.lo) / 2;
    ww.inv_gamma = twist_range(w, ww.lo, ww.hi, ww.lo_tt, ww.hi_tt, ww.twisted_lower.data(), ww.twisted_inv_pivot.data());
  }
}

void interleave_window_factors(const std::vector<WireLanes>& packs, const std::vector<WireWindow>& windows,
                               double* sweep_factors) {
  for (const WireLanes& p : packs)
    for (int k = 0; k < p.lanes; ++k) {
      const WireWindow& ww = windows[p.wire[k]];
      double* f = sweep_factors + 2 * p.offset;
      for (int i = ww.lo; i <= ww.hi; ++i) {
        f[(2 * static_cast<std::size_t>(i) + 0) * p.lanes + k] = ww.tt_lower[i];
        f[(2 * static_cast<std::size_t>(i) + 1) * p.lanes + k] = ww.tt_inv_pivot[i];
      }
    }
}

void factor_centred_windows(const CentredPlane& plane, const std::vector<WireLanes>& packs,
                            const std::vector<WireWindow>& windows, double* scratch, double* twin,
                            const std::vector<std::size_t>& twin_at, double* single,
                            const std::vector<std::size_t>& single_at) {
  for (std::size_t pk = 0; pk < packs.size(); ++pk) {
    const WireLanes& p = packs[pk];
    for (int lane = 0; lane < p.lanes; ++lane) {
      const WireWindow& ww = windows[p.wire[lane]];
      if (ww.hi < ww.lo) continue;
      const double share[6] = {ww.lo_ww, ww.lo_wt, ww.lo_tt, ww.hi_ww, ww.hi_wt, ww.hi_tt};  // 0 where not cut
      factor_centred_range(plane, p, lane, ww.lo, ww.hi, share, scratch, twin + twin_at[pk], single + single_at[pk]);
    }
  }
}

namespace {

// The vertical plane's centred factors of its window (factor_centred_windows).
void factor_centred_window(const Model& m, State& s) {
  StepWorkspace& w = *s.work;
  const CentredPlane plane{&m.wires, m.mass.data(), m.inv_mass.data(), centred_shift(m, m.dt)};
  factor_centred_windows(plane, packs_of(m), s.window, w.centred_scratch.data(), w.centred_twin.data(), w.centred_twin_at,
                         w.centred_single.data(), w.centred_single_at);
}

}  // namespace

void update_window(const Model& m, State& s) {
  double x_min = 1e300, x_max = -1e300;
  for (const Pantograph& p : m.pantographs) {
    const double x = s.front - p.position;
    x_min = std::min(x_min, x);
    x_max = std::max(x_max, x);
  }
  if (m.pantographs.empty()) x_min = x_max = s.front;
  const std::vector<double>& sx = m.support_x;
  double lo_x = 0.0, hi_x = 0.0;
  // Whole sections (Model::window_holds_sections): those within a span of a pantograph. Sections
  // touch only through the pantographs, so one ahead is at rest until they reach it and one they
  // have left changes nothing they feel: the contact is the whole line's (to rounding: the
  // window's factors are formed in another order).
  int sec_first = -1, sec_last = -1;
  if (m.window_holds_sections) {
    for (std::size_t k = 0; k < m.sections.size(); ++k)
      if (m.sections[k].start <= x_max + m.longest_span && m.sections[k].end >= x_min - m.longest_span) {
        if (sec_first < 0) sec_first = static_cast<int>(k);
        sec_last = static_cast<int>(k);
      }
    if (sec_first < 0) sec_first = sec_last = 0;  // (the train beyond the line: its first section)
    lo_x = m.sections[sec_first].start;  // (sections lie in line order, each beyond the one before)
    hi_x = m.sections[sec_last].end;
  } else {
    double ahead = 0.0, behind = 0.0;
    window_lengths(m, s.speed, &ahead, &behind);
    lo_x = x_min - behind;
    hi_x = x_max + ahead;
  }
  // Snap outward to supports (whole sections: their end supports themselves).
  const double on = m.window_holds_sections ? 1e-9 : 0.0;
  int first = static_cast<int>(std::upper_bound(sx.begin(), sx.end(), lo_x + on) - sx.begin()) - 1;
  int last = static_cast<int>(std::lower_bound(sx.begin(), sx.end(), hi_x - on) - sx.begin());
  first = std::clamp(first, 0, static_cast<int>(sx.size()) - 1);
  last = std::clamp(last, 0, static_cast<int>(sx.size()) - 1);
  if (first == s.window_first_support && last == s.window_last_support) return;
  const double a = sx[first], b = sx[last];
  s.window_first_support = first;
  s.window_last_support = last;

  for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
    const Wire& w = m.wires[wi];
    WireWindow& ww = s.window[wi];
    const int old_lo = ww.lo, old_hi = ww.hi;
    if (!m.window_holds_sections) {
      set_wire_window(w, a, b, ww);
    } else if (w.section >= sec_first && w.section <= sec_last) {
      set_wire_window(w, w.x.front(), w.x.back(), ww);  // whole: no cut
    } else {
      ww.lo = 0;  // another section: none of its nodes
      ww.hi = -1;
      ww.cut_lo = ww.cut_hi = false;
      ww.meet = -1;
    }
    // Nodes that left the window return to the static state.
    for (int i = old_lo; i <= old_hi; ++i)
      if (i < ww.lo || i > ww.hi) {
        s.u[w.w_dof + i] = 0.0;
        s.v[w.w_dof + i] = 0.0;
      }
  }
  // The window's factors for the step that reads them: the centred solve's, or the half-step
  // sweep's LDL^T of K_theta_theta.
  if (m.scene.numerics.damping == DampingStep::kCentred) factor_centred_window(m, s);
  else interleave_window_factors(packs_of(m), s.window, s.work->sweep_factors.data());
  for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {  // the wires swept from both ends: their two lanes
    WireWindow& ww = s.window[wi];
    if (m.wires[wi].twisted && ww.meet > 0)
      lay_out_twisted(m, window_range(m.wires[wi], ww), ww.twisted_coef.data(), ww.twisted_factors.data());
  }
  // Index lists sized once in make_state (a copied State keeps their size): no allocation. Only
  // the droppers and supports between the window's ends are looked at, so moving the window costs
  // what the window holds, not the line.
  auto inside = [&](int dof) { return in_windows(m.wires, s.window, dof); };
  // The droppers taken at the step's middle report the tension they acted with while the window
  // steps them; the ones it leaves are back in the static state, whose elastic tension is the one
  // (NaN: State::dropper_tension). Those it still holds get theirs again in this step.
  if (!s.dropper_tension.empty())
    for (int j = 0; j < s.window_dropper_count; ++j) s.dropper_tension[s.window_droppers[j]] = std::nan("");
  s.window_dropper_count = select_between(
      m.dropper_order, m.dropper_order_x, a, b,
      [&](int k) { return inside(m.droppers[k].contact_dof) && inside(m.droppers[k].messenger_dof); },
      s.window_droppers.data());
  s.window_spring_count = select_between(
      m.spring_order, m.spring_order_x, a, b, [&](int k) { return inside(m.springs[k].dof); }, s.window_springs.data());
  s.window_clamp_count = select_between(
      m.clamp_order, m.clamp_order_x, a, b,
      [&](int k) { return inside(m.clamps[k].lower_dof) && inside(m.clamps[k].upper_dof); }, s.window_clamps.data());
}

bool in_windows(const std::vector<Wire>& wires, const std::vector<WireWindow>& windows, int dof) {
  for (std::size_t wi = 0; wi < wires.size(); ++wi) {
    const int i = dof - wires[wi].w_dof;
    if (i >= 0 && i < wires[wi].nodes()) return i >= windows[wi].lo && i <= windows[wi].hi;
  }
  return false;
}

int last_beyond(const Model& m, const State& s, bool windowed, const double* u_new) {
  const double* un = u_new ? u_new : s.work->u_next.data();
  const double limit = m.scene.numerics.divergence_limit;
  auto beyond = [&](int i) { return !(std::fabs(un[i]) <= limit); };
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

void commit_window(const Model& m, State& s, const double* u_new, const double* v_new) {
  double* u = s.u.data();
  double* v = s.v.data();
  auto commit = [&](int i0, int i1) {
    for (int i = i0; i < i1; ++i) {
      v[i] = v_new[i];
      u[i] = u_new[i];
    }
  };
  for (std::size_t wi = 0; wi < m.wires.size(); ++wi)
    commit(m.wires[wi].w_dof + s.window[wi].lo, m.wires[wi].w_dof + s.window[wi].hi + 1);
  commit(m.n_catenary_dof, m.n_dof);
}

void wire_elastic_force_window(const Wire& wire, const WireWindow& ww, const double* z, double* f, double* theta) {
  if (ww.hi < ww.lo) return;
  if (wire.twisted && ww.meet > 0) {
    twisted_band_force(window_range(wire, ww), z, f, theta);
    return;
  }
  const double ends[4] = {ww.lo_ww, ww.lo_wt, ww.hi_ww, ww.hi_wt};
  condensed_band_force(wire, ww.lo, ww.hi, ends, ww.tt_lower.data(), ww.tt_inv_pivot.data(), z, f, theta);
}

}  // namespace catenary_sim
