// The wires' banded stiffness (eq. 3): assembled once per wire as 2x2 blocks per node and element,
// and its products, with the massless rotations condensed exactly (an LDL^T of the tridiagonal
// K_theta_theta) or taken as DOFs (lumped rotary inertia).
#include "catenary_sim/core/model/wire_band.hpp"

#include <algorithm>
#include <vector>

#include "catenary_sim/core/model/beam.hpp"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/scene/scene.hpp"
#include "model/twisted_half.hpp"

namespace catenary_sim {

std::vector<double> transition_piece_factors(const Scene& scene, const Wire& w) {
  const std::size_t si = static_cast<std::size_t>(w.section);
  const bool first = transition_piece_at_start(scene, si), last = transition_piece_at_end(scene, si);
  if (!w.is_contact_wire || !(first || last)) return {};
  const SectionSpec& sec = scene.sections[si];
  const SectionSpec::TransitionPiece& piece = *sec.rail_transition_piece;
  const double at_end = piece.end_bending_stiffness / sec.contact_wire.bending_stiffness;
  std::vector<double> factor(w.nodes() - 1, 1.0);
  for (int e = 0; e + 1 < w.nodes(); ++e) {
    const double mid = 0.5 * (w.x[e] + w.x[e + 1]);
    const double s = std::min(first ? mid - w.x.front() : 1e300, last ? w.x.back() - mid : 1e300);
    if (s < piece.length) factor[e] = at_end + (1.0 - at_end) * s / piece.length;
  }
  return factor;
}

// ei_factor: per element, a multiplier of EI (a worn contact wire, a rail's transition piece);
// empty = the wire's EI.
void assemble_band(Wire& w, const std::vector<double>& ei_factor) {
  const int n = w.nodes();
  w.d_ww.assign(n, 0.0);
  w.d_wt.assign(n, 0.0);
  w.d_tt.assign(n, 0.0);
  w.e_ww.assign(n - 1, 0.0);
  w.e_wt.assign(n - 1, 0.0);
  w.e_tw.assign(n - 1, 0.0);
  w.e_tt.assign(n - 1, 0.0);
  for (int e = 0; e + 1 < n; ++e) {
    const double ei = w.spec.bending_stiffness * (ei_factor.empty() ? 1.0 : ei_factor[e]);
    const Matrix4 k = beam_stiffness(w.x[e + 1] - w.x[e], ei, w.spec.tension);
    w.d_ww[e] += k[0][0];
    w.d_wt[e] += k[0][1];
    w.d_tt[e] += k[1][1];
    w.d_ww[e + 1] += k[2][2];
    w.d_wt[e + 1] += k[2][3];
    w.d_tt[e + 1] += k[3][3];
    w.e_ww[e] = k[0][2];
    w.e_wt[e] = k[0][3];
    w.e_tw[e] = k[1][2];
    w.e_tt[e] = k[1][3];
  }
  // LDL^T of the tridiagonal K_theta_theta, for condensing massless rotations.
  w.tt_inv_pivot.assign(n, 0.0);
  w.tt_lower.assign(n, 0.0);
  double d = w.d_tt[0];
  w.tt_inv_pivot[0] = 1.0 / d;
  for (int i = 1; i < n; ++i) {
    const double l = w.e_tt[i - 1] / d;
    d = w.d_tt[i] - l * w.e_tt[i - 1];
    w.tt_lower[i] = l;
    w.tt_inv_pivot[i] = 1.0 / d;
  }
}

int Wire::element_at(double xs) const {
  const int n = nodes();
  const auto it = std::upper_bound(x.begin(), x.end(), xs);
  const int e = static_cast<int>(it - x.begin()) - 1;
  return std::clamp(e, 0, n - 2);
}

namespace {

// The vertical-displacement rows of the band product, f_w -= K_ww w + K_wt theta, over nodes
// lo..hi, less the diagonal shares of elements left out at the ends (ww, wt at lo, then at hi).
void band_w_rows(const Wire& wire, int lo, int hi, const double end_correction[4], const double* w,
                 const double* theta, double* fw) {
  const double* dww = wire.d_ww.data();
  const double* dwt = wire.d_wt.data();
  const double* eww = wire.e_ww.data();
  const double* ewt = wire.e_wt.data();
  const double* etw = wire.e_tw.data();
  auto dww_at = [&](int i) { return dww[i] - (i == lo ? end_correction[0] : 0.0) - (i == hi ? end_correction[2] : 0.0); };
  auto dwt_at = [&](int i) { return dwt[i] - (i == lo ? end_correction[1] : 0.0) - (i == hi ? end_correction[3] : 0.0); };
  fw[lo] -= dww_at(lo) * w[lo] + dwt_at(lo) * theta[lo];
  for (int i = lo + 1; i <= hi; ++i) {
    const int e = i - 1;
    fw[i] -= dww_at(i) * w[i] + dwt_at(i) * theta[i] + eww[e] * w[e] + etw[e] * theta[e];
    fw[e] -= eww[e] * w[i] + ewt[e] * theta[i];
  }
}

}  // namespace

void condensed_band_force(const Wire& wire, int lo, int hi, const double end_correction[4], const double* lower,
                          const double* inv_pivot, const double* z, double* f, double* theta) {
  const double* w = z + wire.w_dof;
  double* fw = f + wire.w_dof;
  const double* dwt = wire.d_wt.data();
  const double* ewt = wire.e_wt.data();
  const double* etw = wire.e_tw.data();
  // Diagonal blocks less the share of elements left out at the ends (a window's cut).
  auto dwt_at = [&](int i) { return dwt[i] - (i == lo ? end_correction[1] : 0.0) - (i == hi ? end_correction[3] : 0.0); };
  // Massless rotations, condensed exactly: K_tt theta = -K_tw w (tridiagonal, LDL^T given).
  double prev = 0.0;
  for (int i = lo; i <= hi; ++i) {
    double r = -dwt_at(i) * w[i];
    if (i < hi) r -= etw[i] * w[i + 1];
    if (i > lo) r -= ewt[i - 1] * w[i - 1];
    prev = r - (i > lo ? lower[i] * prev : 0.0);
    theta[i] = prev;
  }
  theta[hi] *= inv_pivot[hi];
  for (int i = hi - 1; i >= lo; --i) theta[i] = theta[i] * inv_pivot[i] - lower[i + 1] * theta[i + 1];
  band_w_rows(wire, lo, hi, end_correction, w, theta, fw);
}

double twist_range(const Wire& w, int lo, int hi, double tt_lo, double tt_hi, double* lower, double* inv_pivot) {
  const int meet = (hi - lo) / 2;
  // The mirrored K_theta_theta (x' = L - x negates each rotation: its entries are the wire's, in
  // reverse order) from its first node, as assemble_band's and set_wire_window's LDL^T.
  double d = w.d_tt[hi] - tt_hi;
  lower[0] = 0.0;
  inv_pivot[0] = 1.0 / d;
  for (int k = 1; k <= meet; ++k) {
    const int t = hi - k;
    const double e = w.e_tt[t], l = e / d;
    d = w.d_tt[t] - l * e;
    lower[k] = l;
    inv_pivot[k] = 1.0 / d;
  }
  double d_plus = w.d_tt[lo] - tt_lo;
  for (int i = lo + 1; i <= lo + meet; ++i) {
    const double l = w.e_tt[i - 1] / d_plus;
    d_plus = w.d_tt[i] - l * w.e_tt[i - 1];
  }
  // The meeting row with both neighbours eliminated: gamma = d+ + d- - d (Parlett and Dhillon,
  // "Fernando's solution to Wilkinson's problem", 1997; Meurant 1992's twisted factorisation).
  return 1.0 / (d_plus + d - w.d_tt[lo + meet]);
}

void twist_condensation(Wire& w) {
  const int top = w.nodes() - 1;
  w.twisted = true;
  w.twisted_meeting = top / 2;
  w.twisted_lower.assign(w.twisted_meeting + 1, 0.0);
  w.twisted_inv_pivot.assign(w.twisted_meeting + 1, 0.0);
  w.twisted_inv_gamma = twist_range(w, 0, top, 0.0, 0.0, w.twisted_lower.data(), w.twisted_inv_pivot.data());
}

TwistedRange whole_wire_range(const Wire& w) {
  TwistedRange r;
  r.w = &w;
  r.lo = 0;
  r.hi = w.nodes() - 1;
  r.meet = w.twisted_meeting;
  r.end_ww[0] = w.d_ww[0];
  r.end_wt[0] = w.d_wt[0];
  r.end_ww[1] = w.d_ww[r.hi];
  r.end_wt[1] = -w.d_wt[r.hi];
  r.lower[0] = w.tt_lower.data();
  r.inv_pivot[0] = w.tt_inv_pivot.data();
  r.lower[1] = w.twisted_lower.data();
  r.inv_pivot[1] = w.twisted_inv_pivot.data();
  r.inv_gamma = w.twisted_inv_gamma;
  return r;
}

TwistedRange window_range(const Wire& w, const WireWindow& ww) {
  TwistedRange r;
  r.w = &w;
  r.lo = ww.lo;
  r.hi = ww.hi;
  r.meet = ww.meet;
  r.end_ww[0] = w.d_ww[ww.lo] - ww.lo_ww;
  r.end_wt[0] = w.d_wt[ww.lo] - ww.lo_wt;
  r.end_ww[1] = w.d_ww[ww.hi] - ww.hi_ww;
  r.end_wt[1] = -(w.d_wt[ww.hi] - ww.hi_wt);
  r.lower[0] = ww.tt_lower.data() + ww.lo;
  r.inv_pivot[0] = ww.tt_inv_pivot.data() + ww.lo;
  r.lower[1] = ww.twisted_lower.data();
  r.inv_pivot[1] = ww.twisted_inv_pivot.data();
  r.inv_gamma = ww.inv_gamma;
  return r;
}

// Each half as condensed_band_force on its own nodes, in the fused kernel's order of operations
// (TwistedLone in engine/wire_lanes.cpp: the same bits), the meeting node's rotation from both
// sides' eliminations.
void twisted_band_force(const TwistedRange& range, const double* z, double* f, double* theta) {
  const int meet = range.meet;
  const double* zw = z + range.w->w_dof;
  double* fw = f + range.w->w_dof;
  const TwistedHalf half[2] = {{range, false}, {range, true}};
  double r_meet[2], y_meet[2], th_before[2];
  // Forward (K_tt theta = -K_tw z, L of LDL^T) up to the meeting in each half; theta holds y.
  for (int lane = 0; lane < 2; ++lane) {
    const TwistedHalf& h = half[lane];
    auto zs = [&](int k) { return zw[h.node(k)]; };
    double y = -h.dwt(0) * zs(0) - h.etw(0) * zs(1);
    theta[h.node(0)] = y;
    for (int k = 1; k < meet; ++k) {
      const double r = (-h.dwt(k) * zs(k) - h.etw(k) * zs(k + 1)) - h.ewt(k - 1) * zs(k - 1);
      y = r - h.lower(k) * y;
      theta[h.node(k)] = y;
    }
    r_meet[lane] = (-h.dwt(meet) * zs(meet) - h.etw(meet) * zs(meet + 1)) - h.ewt(meet - 1) * zs(meet - 1);
    y_meet[lane] = r_meet[lane] - h.lower(meet) * y;
  }
  // The meeting node: y+ + y- - r over gamma (lane 1's y is the mirrored wire's, -y-).
  const double t_meet = ((y_meet[0] - y_meet[1]) - r_meet[0]) * range.inv_gamma;
  for (int lane = 0; lane < 2; ++lane) {
    const TwistedHalf& h = half[lane];
    th_before[lane] = theta[h.node(meet - 1)] * h.inv_pivot(meet - 1) - h.lower(meet) * (lane ? -t_meet : t_meet);
  }
  {
    const TwistedHalf& h = half[0];
    const int c = h.node(meet);
    const double A = ((h.dww(meet) * zw[c] + h.dwt(meet) * t_meet) + h.eww(meet - 1) * zw[c - 1]) +
                     h.etw(meet - 1) * th_before[0];
    const double B = h.eww(meet) * zw[c + 1] + h.ewt(meet) * -th_before[1];
    fw[c] = (fw[c] - A) - B;
    theta[c] = t_meet;
  }
  // Back from the meeting in each half: rotation k, and node k + 1's band force behind it.
  for (int lane = 0; lane < 2; ++lane) {
    const TwistedHalf& h = half[lane];
    auto zs = [&](int k) { return zw[h.node(k)]; };
    double th2 = lane ? -t_meet : t_meet, th1 = th_before[lane];
    for (int k = meet - 2; k >= 0; --k) {
      const double th0 = theta[h.node(k)] * h.inv_pivot(k) - h.lower(k + 1) * th1;
      const int j = k + 1;
      const double A = ((h.dww(j) * zs(j) + h.dwt(j) * th1) + h.eww(k) * zs(k)) + h.etw(k) * th0;
      const double B = h.eww(j) * zs(j + 1) + h.ewt(j) * th2;
      double& fj = fw[h.node(j)];
      fj = (fj - A) - B;
      theta[h.node(j)] = lane ? -th1 : th1;
      th2 = th1;
      th1 = th0;
    }
    const double A = h.dww(0) * zs(0) + h.dwt(0) * th1;
    const double B = h.eww(0) * zs(1) + h.ewt(0) * th2;
    double& f0 = fw[h.node(0)];
    f0 = (f0 - A) - B;
    theta[h.node(0)] = lane ? -th1 : th1;
  }
}

void wire_elastic_force(const Wire& wire, const double* z, double* f, double* theta) {
  const int n = wire.nodes();
  if (wire.theta_dof < 0 && wire.twisted_meeting >= 0) {
    twisted_band_force(whole_wire_range(wire), z, f, theta);
    return;
  }
  if (wire.theta_dof < 0) {
    static constexpr double kNone[4] = {0.0, 0.0, 0.0, 0.0};
    condensed_band_force(wire, 0, n - 1, kNone, wire.tt_lower.data(), wire.tt_inv_pivot.data(), z, f, theta);
    return;
  }
  const double* w = z + wire.w_dof;
  double* fw = f + wire.w_dof;
  const double* dwt = wire.d_wt.data();
  const double* ewt = wire.e_wt.data();
  const double* etw = wire.e_tw.data();
  // Rotations as DOFs (HRZ rotary inertia): the full band.
  const double* t = z + wire.theta_dof;
  double* ft = f + wire.theta_dof;
  const double* dtt = wire.d_tt.data();
  const double* ett = wire.e_tt.data();
  for (int i = 0; i < n; ++i) ft[i] -= dwt[i] * w[i] + dtt[i] * t[i];
  for (int e = 0; e + 1 < n; ++e) {
    ft[e] -= etw[e] * w[e + 1] + ett[e] * t[e + 1];
    ft[e + 1] -= ewt[e] * w[e] + ett[e] * t[e];
  }
  std::copy(t, t + n, theta);
  static constexpr double kNone[4] = {0.0, 0.0, 0.0, 0.0};
  band_w_rows(wire, 0, n - 1, kNone, w, t, fw);
}

void apply_stiffness(const Model& m, double front, const double* x, double* y, double* scratch, bool explicit_part) {
  std::fill(y, y + m.n_dof, 0.0);
  for (const Wire& w : m.wires) wire_elastic_force(w, x, y, scratch);  // y = -K x so far
  const bool skip_supports = explicit_part && m.takes_supports_at_middle;
  const bool skip_droppers = explicit_part && m.takes_links_at_middle;
  for (std::size_t k = 0; k < m.springs.size(); ++k) {
    const SupportSpring& s = m.springs[k];
    if (!(skip_supports && m.support_at_middle[k])) y[s.dof] -= s.stiffness * x[s.dof];
  }
  for (std::size_t k = 0; k < m.droppers.size(); ++k) {
    if (skip_droppers && m.dropper_at_middle[k]) continue;
    const Dropper& d = m.droppers[k];
    const double t = d.stiffness * (x[d.messenger_dof] - x[d.contact_dof]);
    y[d.contact_dof] += t;
    y[d.messenger_dof] -= t;
  }
  const bool skip_clamps = explicit_part && m.takes_links_at_middle;
  for (std::size_t k = 0; k < m.clamps.size(); ++k) {
    if (skip_clamps && m.clamp_at_middle[k]) continue;
    const WireClamp& c = m.clamps[k];
    const double t = c.stiffness * (x[c.upper_dof] - x[c.lower_dof]);
    y[c.lower_dof] += t;
    y[c.upper_dof] -= t;
  }
  std::vector<int> node(m.max_contact_nodes);
  std::vector<double> weight(m.max_contact_nodes);
  for (const Pantograph& p : m.pantographs) {
    if (p.moving_force) continue;
    for (int i = 0; i < p.masses_count(); ++i) {
      const int a = p.first_dof + i;
      const double below = i + 1 < p.masses_count() ? x[a + 1] : 0.0;
      const double c = p.stiffness[i] * (below - x[a]);
      y[a] += c;
      if (i + 1 < p.masses_count()) y[a + 1] -= c;
    }
    for (const Head& h : p.heads) {
      const double c = h.stiffness * (x[p.first_dof] - x[h.dof]);
      y[h.dof] += c;
      y[p.first_dof] -= c;
    }
    for (int ci : p.collectors) {
      const int hd = m.collectors[ci].dof;
      const double xc = front - p.position + m.collectors[ci].offset;
      for (int wi : m.contact_wires) {
        const Wire& w = m.wires[wi];
        const int n = contact_weights(w, m.rub_length, xc, node.data(), weight.data());
        double yw = 0.0;
        for (int k = 0; k < n; ++k) yw += weight[k] * x[w.w_dof + node[k]];
        if (n == 0) continue;
        const double f = m.contact_stiffness * (x[hd] - yw);
        y[hd] -= f;
        for (int k = 0; k < n; ++k) y[w.w_dof + node[k]] += f * weight[k];
      }
    }
  }
  for (int i = 0; i < m.n_dof; ++i) y[i] = -y[i];
}

}  // namespace catenary_sim
