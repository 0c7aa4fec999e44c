#include "util/format.hpp"
#include "catenary_sim/core/model/model.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <limits>
#include <sstream>

#include "catenary_sim/core/model/beam.hpp"
#include "catenary_sim/core/model/newmark_matrix.hpp"
#include "catenary_sim/core/model/lateral.hpp"
#include "catenary_sim/core/model/stability.hpp"
#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/model/statics.hpp"
#include "model/normal_errors.hpp"
#include "engine/window.hpp"
#include "engine/centred_damping.hpp"
#include "engine/wire_lanes.hpp"

namespace catenary_sim {
namespace {


// Node stations of one tension section: every support and dropper is a node; the segments
// between them are split into equal elements no longer than the requested length.
std::vector<double> mesh_section(const SectionSpec& sec, double element_length, std::vector<double>& support_x) {
  std::vector<double> breaks;
  double x0 = sec.start;
  support_x.assign(1, x0);
  for (std::size_t i = 0; i < sec.spans.size(); ++i) {
    breaks.push_back(x0);
    if (sec.droppers)
      for (double p : sec.droppers->positions[i]) breaks.push_back(x0 + p);
    x0 += sec.spans[i];
    support_x.push_back(x0);
  }
  breaks.push_back(x0);
  std::vector<double> x;
  for (std::size_t i = 0; i + 1 < breaks.size(); ++i) {
    const double len = breaks[i + 1] - breaks[i];
    const int n = std::max(1, static_cast<int>(std::ceil(len / element_length - 1e-9)));
    for (int k = 0; k < n; ++k) x.push_back(breaks[i] + len * k / n);
  }
  x.push_back(x0);
  return x;
}

int node_at(const std::vector<double>& x, double xs) {
  const auto it = std::lower_bound(x.begin(), x.end(), xs - 1e-9);
  return static_cast<int>(it - x.begin());
}

// ei_factor: per element, a multiplier of EI (a worn contact wire); empty = the wire's EI.
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

}  // namespace

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

void wire_elastic_force(const Wire& wire, const double* z, double* f, double* theta) {
  const int n = wire.nodes();
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

int contact_weights(const Wire& wire, double rub_length, double xc, int* node, double* weight) {
  const double x0 = wire.x.front(), x1 = wire.x.back();
  if (rub_length <= 0.0) {
    if (xc < x0 || xc > x1) return 0;
    const int e = wire.element_at(xc);
    const double xi = (xc - wire.x[e]) / (wire.x[e + 1] - wire.x[e]);
    node[0] = e;
    node[1] = e + 1;
    weight[0] = 1.0 - xi;
    weight[1] = xi;
    return 2;
  }
  const double a = xc - 0.5 * rub_length, b = xc + 0.5 * rub_length;
  if (b <= x0 || a >= x1) return 0;
  const int ea = wire.element_at(a), eb = wire.element_at(b);
  const int count = eb - ea + 2;
  for (int k = 0; k < count; ++k) {
    node[k] = ea + k;
    weight[k] = 0.0;
  }
  // Exact integrals of f(s) = (1 + cos(2 pi s / l)) / l (eq. 13) against the linear
  // interpolation of the wire between nodes.
  const double kw = 2.0 * M_PI / rub_length, il = 1.0 / rub_length;
  auto F0 = [&](double s) { return (s + std::sin(kw * s) / kw) * il; };
  auto F1 = [&](double s) { return (0.5 * s * s + s * std::sin(kw * s) / kw + std::cos(kw * s) / (kw * kw)) * il; };
  double total = 0.0;
  for (int e = ea; e <= eb; ++e) {
    const double xa = wire.x[e], xb = wire.x[e + 1];
    const double s1 = std::max(a, xa) - xc, s2 = std::min(b, xb) - xc;
    if (s2 <= s1) continue;
    const double i0 = F0(s2) - F0(s1), i1 = F1(s2) - F1(s1);
    const double right = (i1 + (xc - xa) * i0) / (xb - xa);
    weight[e - ea] += i0 - right;
    weight[e - ea + 1] += right;
    total += i0;
  }
  if (total <= 1e-12) return 0;
  // Renormalise where the rub zone hangs over the end of the wire, so that eq. 11 holds.
  for (int k = 0; k < count; ++k) weight[k] /= total;
  return count;
}

double lowest_design_height(const Model& m, double xc, int* wire) {
  std::vector<int> node(m.max_contact_nodes);
  std::vector<double> weight(m.max_contact_nodes);
  double lowest = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < m.contact_wires.size(); ++k) {
    const Wire& w = m.wires[m.contact_wires[k]];
    const int cnt = contact_weights(w, m.rub_length, xc, node.data(), weight.data());
    if (cnt == 0) continue;
    double y = 0.0;
    for (int a = 0; a < cnt; ++a) y += weight[a] * w.height[node[a]];
    if (y < lowest) {
      lowest = y;
      if (wire) *wire = static_cast<int>(k);
    }
  }
  return lowest;
}

void apply_stiffness(const Model& m, double front, const double* x, double* y, double* scratch) {
  std::fill(y, y + m.n_dof, 0.0);
  for (const Wire& w : m.wires) wire_elastic_force(w, x, y, scratch);  // y = -K x so far
  for (const SupportSpring& s : m.springs) y[s.dof] -= s.stiffness * x[s.dof];
  for (const Dropper& d : m.droppers) {
    const double t = d.stiffness * (x[d.messenger_dof] - x[d.contact_dof]);
    y[d.contact_dof] += t;
    y[d.messenger_dof] -= t;
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

namespace {

// Offsets from the train front (m) of the foremost and rearmost collectors of all pantographs
// (collector station - front); both 0 without collectors.
void collector_extent(const Scene& scene, double* lead, double* rear) {
  bool first = true;
  *lead = *rear = 0.0;
  auto add = [&](double off) {
    *lead = first ? off : std::max(*lead, off);
    *rear = first ? off : std::min(*rear, off);
    first = false;
  };
  for (const PantographSpec& p : scene.pantographs) {
    for (const CollectorSpec& c : p.collectors) add(c.offset - p.position);
    // Strips on heads: their offsets are from the head's centre (without this a head could start
    // or end off the line, its strip touching nothing and the head rising on its preload).
    for (const HeadSpec& h : p.heads)
      for (const CollectorSpec& c : h.collectors) add(h.offset + c.offset - p.position);
  }
}

// Spans at each end of an endless line's block that the window never reaches: the anchors'
// effect on the design statics (messenger heights, dropper lengths) falls by about a thousand
// per span, so from the third span on the spans are identical to well under a micrometre.
constexpr int kEndlessMargin = 3;

// An endless line moves its state back a span at a time, which is exact only if the block's
// spans are identical where the window goes: same nodes, stations relative to the span, design
// heights (to 1 um, against wire motions of millimetres) and masses; same droppers. Sets
// Model::span_nodes.
void check_endless_block(Model& m) {
  const double span = m.endless_span;
  const int count = static_cast<int>(m.scene.spans.size());
  auto fail = [&](const std::string& what) {
    throw SceneError("line.endless: the model's spans are not identical (" + what +
                     "); the state cannot be moved back a span. Report this with the scene");
  };
  for (const Wire& w : m.wires) {
    if (static_cast<int>(w.support_nodes.size()) != count + 1) fail(w.name + ": supports");
    const int first = kEndlessMargin - 1, last = count - kEndlessMargin;  // spans compared with the next
    const int ns = w.support_nodes[first + 1] - w.support_nodes[first];
    for (int k = first; k < last; ++k) {
      if (w.support_nodes[k + 1] - w.support_nodes[k] != ns || w.support_nodes[k + 2] - w.support_nodes[k + 1] != ns)
        fail(w.name + ": nodes per span");
      for (int i = w.support_nodes[k]; i < w.support_nodes[k + 1]; ++i) {
        const int j = i + ns;
        if (std::fabs(w.x[j] - w.x[i] - span) > 1e-9 * span || std::fabs(w.height[j] - w.height[i]) > 1e-6 ||
            std::fabs(m.mass[w.w_dof + j] - m.mass[w.w_dof + i]) > 1e-6 * m.mass[w.w_dof + i])
          fail(w.name + " at x = " + fmt(w.x[i]) + " m");
      }
    }
    m.span_nodes.push_back(ns);
  }
  const double tol = 1e-6;
  for (std::size_t k = 0; k < m.droppers.size(); ++k)
    for (std::size_t j = k + 1; j < m.droppers.size(); ++j) {
      const Dropper& a = m.droppers[k];
      const Dropper& b = m.droppers[j];
      if (a.span < kEndlessMargin - 1 || a.span >= count - kEndlessMargin || b.span != a.span + 1 || std::fabs(b.x - a.x - span) > 1e-9 * span) continue;
      if (std::fabs(b.static_tension - a.static_tension) > tol * std::fabs(a.static_tension) + 1e-9 ||
          std::fabs(b.stiffness - a.stiffness) > tol * a.stiffness)
        fail("dropper at x = " + fmt(a.x) + " m");
    }
}

}  // namespace

void analysis_section(const Model& m, double* x0, double* x1) {
  const OutputSpec& o = m.scene.output;
  if (!m.endless) {
    *x0 = m.support_x[m.scene.analysis_first()];
    *x1 = m.support_x[m.scene.analysis_last()];
    return;
  }
  const double span = m.endless_span;
  if (o.analysis_first_span && o.analysis_last_span) {
    *x0 = *o.analysis_first_span * span;
    *x1 = *o.analysis_last_span * span;
    return;
  }
  // The pass's spans but two at each end, as on a finite line.
  const double start = m.train_start + m.initial_line_offset + m.rear_collector_offset;
  *x0 = (std::ceil(start / span - 1e-9) + 2) * span;
  *x1 = (std::floor(m.train_end / span + 1e-9) - 2) * span;
  if (*x1 <= *x0) {
    *x0 = start;
    *x1 = m.train_end;
  }
}

Model build_model(const Scene& scene) { return build_model(scene, BuildOptions{}); }

std::string speed_warning(const Model& m, double speed) {
  if (!(speed > 0.7 * m.wave_speed)) return "";
  std::ostringstream s;
  s.precision(3);
  s << "train speed " << speed * 3.6 << " km/h is " << speed / m.wave_speed << " of the contact wire's wave speed c = "
    << m.wave_speed * 3.6 << " km/h: above 0.7 c is outside design practice (the wave ahead of the pantograph steepens "
    << "and contact is lost as the speed nears c)";
  return s.str();
}

namespace {

// Spectral representation of a random profile (Shinozuka): sum_j a_j cos(k_j x + phi_j) with the
// one-sided power-law spectrum S(k) ~ k^-n shared among kHarmonics bands equally spaced in log k
// between 2 pi / wavelength_max and 2 pi / wavelength_min, a_j^2 / 2 = S(k_j) dk_j scaled so that
// sum a_j^2 / 2 = rms^2; each k_j drawn inside its band (no common period) and each phase uniform.
std::vector<double> irregularity_profile(const IrregularitySpec& ir, NormalErrors& gen, const std::vector<Wire>& wires) {
  std::vector<double> out;
  if (!ir.profile.empty()) {
    for (const Wire& w : wires)
      if (w.is_contact_wire)
        for (double x : w.x) out.push_back(ir.profile.at(x));
    return out;
  }
  constexpr int kHarmonics = 256;
  const double k0 = 2.0 * M_PI / ir.wavelength_max, k1 = 2.0 * M_PI / ir.wavelength_min;
  const double step = std::log(k1 / k0) / kHarmonics;
  std::vector<double> k(kHarmonics), a(kHarmonics), phase(kHarmonics);
  double power = 0.0;
  for (int j = 0; j < kHarmonics; ++j) {
    const double lo = k0 * std::exp(j * step), hi = k0 * std::exp((j + 1) * step);
    k[j] = lo + (hi - lo) * gen.uniform();
    phase[j] = 2.0 * M_PI * gen.uniform();
    a[j] = std::pow(0.5 * (lo + hi), -ir.exponent) * (hi - lo);  // S(k_j) dk_j, scaled below
    power += a[j];
  }
  for (double& aj : a) aj = std::sqrt(2.0 * aj / power) * ir.rms;
  for (const Wire& w : wires) {
    if (!w.is_contact_wire) continue;
    for (double x : w.x) {
      double r = 0.0;
      for (int j = 0; j < kHarmonics; ++j) r += a[j] * std::cos(k[j] * x + phase[j]);
      out.push_back(r);
    }
  }
  return out;
}

// The line as built: the design statics set the dropper lengths and support heights; the errors
// act on the built line through the constant load (at u = 0 it no longer balances, and the eq. 23
// statics find where the built line hangs). A dropper longer by e carries k e less at the design
// geometry; a steady arm assembled e higher pushes k_A e more (eq. 4 with y0 + e); a point mass
// adds its mass and weight to the nearest contact-wire node.
void apply_imperfections(const Scene& scene, Model& m, const std::vector<bool>& fixed) {
  const ImperfectionSpec& im = scene.imperfections;
  if (!im.any()) return;
  NormalErrors shared(im.seed);
  NormalErrors own_droppers(im.dropper_length_seed.value_or(0)), own_arms(im.support_height_seed.value_or(0));
  NormalErrors& dropper_normal = im.dropper_length_seed ? own_droppers : shared;
  NormalErrors& arm_normal = im.support_height_seed ? own_arms : shared;
  std::vector<int> order(m.droppers.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = static_cast<int>(k);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return m.droppers[a].x < m.droppers[b].x; });
  if (!im.dropper_length_errors.empty() && im.dropper_length_errors.size() != order.size())
    throw SceneError("scene field 'imperfections.dropper_length_errors' = (" + std::to_string(im.dropper_length_errors.size()) +
                     " values): one per dropper in line order (" + std::to_string(order.size()) + ")");
  if ((im.dropper_length_std > 0.0 || !im.dropper_length_errors.empty()) && order.empty())
    throw SceneError("scene field 'imperfections.dropper_length_std': the scene has no droppers");
  for (std::size_t j = 0; j < order.size(); ++j) {
    const double e = !im.dropper_length_errors.empty() ? im.dropper_length_errors[j]
                     : im.dropper_length_std > 0.0     ? dropper_normal.next(im.dropper_length_std)
                                                       : 0.0;
    Dropper& d = m.droppers[order[j]];
    if (e >= d.unstretched_length)
      throw SceneError("scene field 'imperfections.dropper_length_errors' (dropper at " + fmt(d.x) + " m) = " + fmt(e) +
                       ": allowed below the dropper's length " + fmt(d.unstretched_length) + " m");
    d.static_tension -= d.stiffness * e;  // may go negative: a dropper too long hangs slack
  }
  std::vector<int> arms;
  for (std::size_t k = 0; k < m.springs.size(); ++k)
    if (m.springs[k].steady_arm) arms.push_back(static_cast<int>(k));
  std::stable_sort(arms.begin(), arms.end(), [&](int a, int b) { return m.springs[a].x < m.springs[b].x; });
  if (!im.support_height_errors.empty() && im.support_height_errors.size() != arms.size())
    throw SceneError("scene field 'imperfections.support_height_errors' = (" + std::to_string(im.support_height_errors.size()) +
                     " values): one per steady arm in line order (" + std::to_string(arms.size()) + ")");
  if ((im.support_height_std > 0.0 || !im.support_height_errors.empty()) && arms.empty())
    throw SceneError("scene field 'imperfections.support_height_std': the scene has no steady arms (elastic contact-wire "
                     "supports; rigid supports cannot be displaced)");
  for (std::size_t j = 0; j < arms.size(); ++j) {
    const double e = !im.support_height_errors.empty() ? im.support_height_errors[j]
                     : im.support_height_std > 0.0     ? arm_normal.next(im.support_height_std)
                                                       : 0.0;
    m.load[m.springs[arms[j]].dof] += m.springs[arms[j]].stiffness * e;
  }
  const double g = scene.gravity;
  const IrregularitySpec& ir = im.contact_wire_irregularity;
  if (ir.any()) {
    NormalErrors own_irregularity(ir.seed.value_or(0));
    const std::vector<double> r = irregularity_profile(ir, ir.seed ? own_irregularity : shared, m.wires);
    std::size_t at = 0;
    for (Wire& w : m.wires) {
      if (!w.is_contact_wire) continue;
      for (int i = 0; i < w.nodes(); ++i) w.height[i] += r[at++];
    }
  }
  for (const PointMassSpec& pm : im.point_masses) {
    const Wire& w = m.wires[m.contact_wires.front()];
    const auto it = std::lower_bound(w.x.begin(), w.x.end(), pm.station);
    int node = static_cast<int>(it - w.x.begin());
    if (node == w.nodes() || (node > 0 && pm.station - w.x[node - 1] < w.x[node] - pm.station)) --node;
    const int dof = w.w_dof + node;
    if (fixed[dof]) continue;  // on a rigid support: held, no dynamic effect
    m.mass[dof] += pm.mass;
    m.load[dof] -= g * pm.mass;
  }
}

Model build_model_unchecked(const Scene& scene_in, const BuildOptions& options) {
  Scene scene = scene_in;
  if (scene.sections.empty()) {
    // A Scene filled in code with the one-section fields only.
    SectionSpec sec;
    sec.spans = scene.spans;
    sec.contact_wire = scene.contact_wire;
    sec.messenger = scene.messenger;
    sec.droppers = scene.droppers;
    sec.steady_arms = scene.steady_arms;
    sec.messenger_supports = scene.messenger_supports;
    if (sec.droppers && sec.droppers->positions.size() == 1 && sec.spans.size() > 1)
      sec.droppers->positions.assign(sec.spans.size(), sec.droppers->positions.front());
    scene.sections.push_back(sec);
  }
  validate(scene);  // as given (an endless line's block and stations are made below)
  Model m;
  double endless_front = 0.0;  // train front at the start, station along the endless line
  if (scene.endless) {
    // A block of equal spans: `margin` spans at each end keep the anchors out of the window's
    // reach (kEndlessMargin); the rearmost collector stays within [home, home + span) (step() moves the state back
    // a span when it leaves), so the block must hold the window behind it (B spans, one more for
    // snapping to supports), the train (S) and the window ahead (A) at any speed a command allows.
    const double span = scene.spans.front();
    const double c = std::sqrt(scene.contact_wire.tension / scene.contact_wire.linear_mass);
    double ahead_slow = 0, behind_slow = 0, ahead_fast = 0, behind_fast = 0;
    window_lengths_for(scene.numerics, c, span, 0.0, &ahead_slow, &behind_slow);
    window_lengths_for(scene.numerics, c, span, std::max(scene.train_speed, Simulation::kMaxSpeed), &ahead_fast, &behind_fast);
    double lead = 0.0, rear = 0.0;
    collector_extent(scene, &lead, &rear);
    auto spans_for = [&](double length) { return static_cast<int>(std::ceil(length / span - 1e-9)); };
    const int margin = kEndlessMargin, behind = spans_for(std::max(behind_slow, behind_fast)) + 1;
    // In a turbulent wind the lateral plane's window reaches a gust lead further (lateral.hpp),
    // snapped outward to a support once more.
    const double gusts = gust_lead_time(scene) * std::max(scene.train_speed, Simulation::kMaxSpeed);
    const int ahead = spans_for(std::max(ahead_slow, ahead_fast) + gusts) + (gusts > 0.0 ? 2 : 1);
    const int train = spans_for(lead - rear);
    // A 3-D line's stagger pattern repeats after `period` supports: the block moves by that many
    // spans (the rearmost collector stays within [home, home + period) spans).
    int period = 1;
    if (scene.stagger) {
      const int a = static_cast<int>(scene.stagger->contact_wire.size());
      const int b = std::max(1, static_cast<int>(scene.stagger->messenger.size()));
      period = a / std::gcd(a, b) * b;
    }
    const int home = margin + behind, count = home + period + train + ahead + margin;
    scene.spans.assign(count, span);
    scene.sections.front().spans = scene.spans;
    if (scene.sections.front().droppers) {
      auto& pos = scene.sections.front().droppers->positions;
      pos.assign(count, pos.front());
      scene.droppers = scene.sections.front().droppers;
    }
    m.endless = true;
    m.endless_span = span;
    m.endless_home = home * span;
    m.endless_shift_spans = period;
    m.rear_collector_offset = rear;
    // The block starts a whole number of spans behind, so that the line's supports stay at
    // multiples of the span.
    endless_front = scene.train_start ? *scene.train_start : -rear;
    const double shift = std::floor((endless_front + rear) / span) - home;
    m.initial_line_offset = shift * span;
    scene.train_start = endless_front - m.initial_line_offset;
  }
  check_model_memory(scene);
  m.scene = scene;
  const bool lumped_rot = scene.numerics.rotary_inertia == RotaryInertia::kLumped;
  m.line_length = scene.line_length();
  m.alpha = scene.rayleigh_alpha;
  m.beta = scene.rayleigh_beta;
  m.contact_stiffness = scene.contact.stiffness;
  m.rub_length = scene.contact.rub_length;
  m.support_x.assign(1, scene.sections.front().start);
  for (double l : scene.spans) m.support_x.push_back(m.support_x.back() + l);
  auto line_support_index = [&](double xs) {
    return static_cast<int>(std::lower_bound(m.support_x.begin(), m.support_x.end(), xs - 1e-9) - m.support_x.begin());
  };

  // Raised contact-wire supports at the transition spans (eq. 6-8): given, measured, or none yet.
  std::vector<double> rise_first(scene.sections.size(), 0.0), rise_last(scene.sections.size(), 0.0);
  if (options.support_rises) {
    for (std::size_t i = 0; i < scene.sections.size(); ++i) {
      rise_first[i] = (*options.support_rises)[2 * i];
      rise_last[i] = (*options.support_rises)[2 * i + 1];
    }
  } else {
    const std::vector<double> r = transition_support_rises(scene);
    for (std::size_t i = 0; i < scene.sections.size(); ++i) {
      rise_first[i] = r[2 * i];
      rise_last[i] = r[2 * i + 1];
    }
  }

  // DOF layout: per wire the vertical displacements, then (lumped rotary inertia only) the
  // rotations; section by section (contact wire(s), then messenger); the pantograph masses last.
  int dof = 0;
  std::vector<std::vector<double>> section_supports(scene.sections.size());
  for (std::size_t si = 0; si < scene.sections.size(); ++si) {
    const SectionSpec& sec = scene.sections[si];
    const std::vector<double> x = mesh_section(sec, scene.numerics.element_length, section_supports[si]);
    Section info;
    info.start = sec.start;
    info.end = sec.end();
    info.rise_first = rise_first[si];
    info.rise_last = rise_last[si];
    const std::string suffix = scene.sections.size() > 1 ? "_s" + std::to_string(si) : "";
    auto add_wire = [&](const std::string& name, const WireSpec& spec, bool contact) {
      Wire w;
      w.name = name;
      w.section = static_cast<int>(si);
      w.is_contact_wire = contact;
      w.spec = spec;
      w.x = x;
      w.w_dof = dof;
      dof += static_cast<int>(x.size());
      if (lumped_rot) {
        w.theta_dof = dof;
        dof += static_cast<int>(x.size());
      }
      for (double sx : section_supports[si]) w.support_nodes.push_back(node_at(x, sx));
      assemble_band(w, {});
      if (contact) m.contact_wires.push_back(static_cast<int>(m.wires.size()));
      else info.messenger = static_cast<int>(m.wires.size());
      info.wires.push_back(static_cast<int>(m.wires.size()));
      m.wires.push_back(std::move(w));
    };
    for (int c = 0; c < sec.contact_wire_count; ++c)
      add_wire("contact_wire" + suffix + (sec.contact_wire_count > 1 ? std::string(1, static_cast<char>('a' + c)) : ""),
               sec.contact_wire, true);
    if (sec.messenger) add_wire("messenger" + suffix, *sec.messenger, false);
    m.sections.push_back(info);
  }
  m.n_catenary_dof = dof;

  for (std::size_t i = 0; i < scene.pantographs.size(); ++i) {
    const PantographSpec& ps = scene.pantographs[i];
    Pantograph p;
    p.name = ps.name;
    p.position = ps.position;
    p.moving_force = ps.moving_force || ps.external;
    p.external = ps.external;
    p.masses = ps.masses;
    p.stiffness = ps.stiffness;
    p.damping = ps.damping;
    p.static_uplift = ps.static_uplift;
    p.aero_coefficient = ps.frame_aero();
    if (!p.moving_force) {
      p.first_dof = dof;
      dof += p.masses_count();
    }
    for (const CollectorSpec& c : ps.collectors) {
      p.collectors.push_back(static_cast<int>(m.collectors.size()));
      m.collectors.push_back(Collector{static_cast<int>(i), c.offset, -1, p.moving_force ? -1 : p.first_dof});
      m.collectors.back().half_working_width = 0.5 * c.working_width.value_or(scene.pantograph_head.working_width);
    }
    // Heads: one DOF each after the chain, on a suspension to the chain's first (top) mass.
    for (std::size_t h = 0; h < ps.heads.size(); ++h) {
      const HeadSpec& hs = ps.heads[h];
      Head head;
      head.dof = dof++;
      head.mass = hs.mass;
      head.stiffness = hs.stiffness;
      head.damping = hs.damping;
      head.aero_coefficient = PantographSpec::head_aero(hs, ps.knee_trailing);
      for (const CollectorSpec& c : hs.collectors) {
        head.collectors.push_back(static_cast<int>(m.collectors.size()));
        p.collectors.push_back(static_cast<int>(m.collectors.size()));
        m.collectors.push_back(Collector{static_cast<int>(i), hs.offset + c.offset, static_cast<int>(h), head.dof});
        m.collectors.back().half_working_width = 0.5 * c.working_width.value_or(scene.pantograph_head.working_width);
      }
      p.heads.push_back(std::move(head));
    }
    m.pantographs.push_back(std::move(p));
  }
  m.n_dof = dof;

  // Lumped masses (HRZ for the beams) and which DOFs are held rigidly: the anchors at both ends
  // of each section, and intermediate supports without a spring.
  m.mass = Eigen::VectorXd::Zero(dof);
  std::vector<bool> fixed(dof, false);
  const double g = scene.gravity;
  for (Wire& w : m.wires) {
    const SectionSpec& sec = scene.sections[w.section];
    const int n = w.nodes();
    for (int e = 0; e + 1 < n; ++e) {
      const double he = w.x[e + 1] - w.x[e];
      m.mass[w.w_dof + e] += beam_translational_mass(he, w.spec.linear_mass);
      m.mass[w.w_dof + e + 1] += beam_translational_mass(he, w.spec.linear_mass);
      if (lumped_rot) {
        m.mass[w.theta_dof + e] += beam_rotary_mass(he, w.spec.linear_mass);
        m.mass[w.theta_dof + e + 1] += beam_rotary_mass(he, w.spec.linear_mass);
      }
    }
    const bool contact = w.is_contact_wire;
    const std::optional<SupportSpec>& spring = contact ? sec.steady_arms : sec.messenger_supports;
    const int ns = static_cast<int>(w.support_nodes.size());
    for (int k = 0; k < ns; ++k) {
      const int node = w.support_nodes[k];
      const bool end = k == 0 || k == ns - 1;  // anchors of the tension section
      if (end || !spring) {
        fixed[w.w_dof + node] = true;
      } else {
        m.mass[w.w_dof + node] += spring->mass;
        SupportSpring sp{w.w_dof + node, spring->stiffness, 0.0, w.x[node], line_support_index(w.x[node]), contact};
        sp.section_support = k;
        m.springs.push_back(sp);
      }
    }
  }

  // Droppers: one per contact wire at each dropper station (a twin contact wire hangs both wires
  // from the same dropper), with clamp masses; lengths and tensions come from the design statics.
  for (std::size_t si = 0; si < scene.sections.size(); ++si) {
    const SectionSpec& sec = scene.sections[si];
    if (!sec.droppers) continue;
    const Section& info = m.sections[si];
    const Wire& mwire = m.wires[info.messenger];
    const DropperSpec& ds = *sec.droppers;
    for (std::size_t i = 0; i < sec.spans.size(); ++i)
      for (double p : ds.positions[i]) {
        const double xd = section_supports[si][i] + p;
        const int node = node_at(mwire.x, xd);
        m.mass[mwire.w_dof + node] += ds.clamp_mass_messenger;
        for (int wi : info.wires) {
          if (wi == info.messenger) continue;
          Dropper d;
          d.x = xd;
          d.section = static_cast<int>(si);
          d.span = static_cast<int>(i);
          d.contact_dof = m.wires[wi].w_dof + node;
          d.messenger_dof = mwire.w_dof + node;
          m.mass[d.contact_dof] += ds.clamp_mass_contact;
          m.droppers.push_back(d);
        }
      }
  }

  // Design statics, section by section. Each contact wire is held at its supports (raised by d at
  // the outer support of a transition span) and, at every dropper, at the presag height of a
  // current span or at the working height in a transition span (where the free wire then rises
  // from its last dropper to the raised support, Fig. 2); the reactions there are the dropper
  // tensions. The messenger carries those tensions and the dropper weight to its supports. The
  // dropper weight depends on its length, which depends on the messenger sag: a few fixed-point
  // passes settle it.
  const double H = scene.contact_wire_height;
  std::vector<double> weight_len(m.droppers.size(), scene.encumbrance);  // lengths the weights use
  std::vector<double> dropper_len = weight_len;                          // geometric lengths
  std::vector<std::vector<double>> react(m.wires.size());
  for (std::size_t si = 0; si < scene.sections.size(); ++si) {
    const SectionSpec& sec = scene.sections[si];
    const Section& info = m.sections[si];
    const double mu = sec.droppers ? sec.droppers->linear_mass : 0.0;
    const int nspan = static_cast<int>(sec.spans.size());
    auto transition = [&](int span) {
      return (span == 0 && sec.first_span_transition) || (span == nspan - 1 && sec.last_span_transition);
    };
    std::vector<std::size_t> mine;
    for (std::size_t k = 0; k < m.droppers.size(); ++k)
      if (m.droppers[k].section == static_cast<int>(si)) mine.push_back(k);
    const int passes = mine.empty() ? 1 : 4;
    for (int pass = 0; pass < passes; ++pass) {
      for (int wi : info.wires) {
        if (wi == info.messenger) continue;
        Wire& w = m.wires[wi];
        const int n = w.nodes();
        std::vector<double> load(n);
        for (int i = 0; i < n; ++i) load[i] = -g * m.mass[w.w_dof + i];
        std::vector<int> pn;
        std::vector<double> ph;
        const int ns = static_cast<int>(w.support_nodes.size());
        for (int k = 0; k < ns; ++k) {
          pn.push_back(w.support_nodes[k]);
          ph.push_back(H + (k == 0 ? info.rise_first : 0.0) + (k == ns - 1 ? info.rise_last : 0.0));
        }
        for (std::size_t k : mine) {
          const Dropper& d = m.droppers[k];
          if (d.contact_dof < w.w_dof || d.contact_dof >= w.w_dof + n) continue;
          const int node = d.contact_dof - w.w_dof;
          load[node] -= 0.5 * g * mu * weight_len[k];
          const double s = (d.x - section_supports[si][d.span]) / sec.spans[d.span];
          pn.push_back(node);
          ph.push_back(transition(d.span) ? H : H - sec.contact_wire.presag * 4.0 * s * (1.0 - s));
        }
        solve_wire_statics(w, load, pn, ph, w.height, w.slope, react[wi]);
        // Dropper tensions: the reactions at the dropper nodes, in the order they were added.
        std::size_t r = static_cast<std::size_t>(ns);
        for (std::size_t k : mine)
          if (m.droppers[k].contact_dof >= w.w_dof && m.droppers[k].contact_dof < w.w_dof + n)
            m.droppers[k].static_tension = react[wi][r++];
      }
      if (info.messenger < 0) break;
      Wire& mwm = m.wires[info.messenger];
      const int n = mwm.nodes();
      std::vector<double> mload(n);
      for (int i = 0; i < n; ++i) mload[i] = -g * m.mass[mwm.w_dof + i];
      for (std::size_t k : mine) {
        const Dropper& d = m.droppers[k];
        mload[d.messenger_dof - mwm.w_dof] -= d.static_tension + 0.5 * g * mu * weight_len[k];
      }
      std::vector<int> mpn(mwm.support_nodes.begin(), mwm.support_nodes.end());
      std::vector<double> mph(mpn.size(), H + scene.encumbrance);
      solve_wire_statics(mwm, mload, mpn, mph, mwm.height, mwm.slope, react[info.messenger]);
      for (std::size_t k : mine) {
        const Dropper& d = m.droppers[k];
        const Wire& cwire = *std::find_if(m.wires.begin(), m.wires.end(), [&](const Wire& w) {
          return d.contact_dof >= w.w_dof && d.contact_dof < w.w_dof + w.nodes();
        });
        dropper_len[k] = mwm.height[d.messenger_dof - mwm.w_dof] - cwire.height[d.contact_dof - cwire.w_dof];
      }
      if (pass + 1 < passes)
        for (std::size_t k : mine) weight_len[k] = dropper_len[k];
    }
  }
  for (std::size_t k = 0; k < m.droppers.size(); ++k) {
    Dropper& d = m.droppers[k];
    const SectionSpec& sec = scene.sections[d.section];
    d.length = dropper_len[k];
    if (d.length <= 0.01)
      throw SceneError("droppers: at x = " + fmt(d.x) + " m the messenger hangs " + fmt(-d.length) +
                       " m below the contact wire (dropper length " + fmt(d.length) +
                       " m): raise line.encumbrance or the messenger tension, or reduce the presag");
    const int nspan = static_cast<int>(sec.spans.size());
    const bool in_transition = (d.span == 0 && sec.first_span_transition) || (d.span == nspan - 1 && sec.last_span_transition);
    if (d.static_tension <= 0.0 && in_transition)
      throw SceneError("droppers: at x = " + fmt(d.x) + " m, in a transition span, the dropper would have to push (static force " +
                       fmt(d.static_tension) + " N): the raised support (rise d = " +
                       fmt(std::max(m.sections[d.section].rise_first, m.sections[d.section].rise_last)) +
                       " m) pulls the wire up past it; lower overlap.support_rise (or overlap.design_force) or hang "
                       "droppers.transition_positions nearer the section's own support");
    if (d.static_tension <= 0.0)
      throw SceneError("droppers: at x = " + fmt(d.x) + " m the dropper would have to push (static force " +
                       fmt(d.static_tension) + " N): contact_wire.presag " + fmt(sec.contact_wire.presag) +
                       " m is not reachable with tension-only droppers; reduce it");
    d.unstretched_length = d.length / (1.0 + d.static_tension / sec.droppers->axial_stiffness);
    d.stiffness = sec.droppers->axial_stiffness / d.unstretched_length;
    // Half the dropper's mass on each end (the length its weight had in the statics, so that the
    // design state is an exact equilibrium).
    m.mass[d.contact_dof] += 0.5 * sec.droppers->linear_mass * weight_len[k];
    m.mass[d.messenger_dof] += 0.5 * sec.droppers->linear_mass * weight_len[k];
  }
  // Support preloads f0 of eq. 4: the static reactions at the elastic supports.
  for (SupportSpring& sp : m.springs) {
    const auto it = std::find_if(m.wires.begin(), m.wires.end(),
                                 [&](const Wire& w) { return sp.dof >= w.w_dof && sp.dof < w.w_dof + w.nodes(); });
    sp.static_force = react[it - m.wires.begin()][sp.section_support];
  }

  // Wear (the line as built, after the design statics): a worn contact wire element is lighter
  // and bends more easily; the constant load below then no longer balances at u = 0, and the
  // eq. 23 statics find where the worn line hangs.
  const WearSpec& wear = scene.imperfections.contact_wire_wear;
  if (wear.any())
    for (Wire& w : m.wires) {
      if (!w.is_contact_wire) continue;
      std::vector<double> ei_factor(w.nodes() - 1, 1.0);
      for (int e = 0; e + 1 < w.nodes(); ++e) {
        const double loss = wear.at(0.5 * (w.x[e] + w.x[e + 1])), he = w.x[e + 1] - w.x[e];
        ei_factor[e] = std::pow(1.0 - loss, wear.ei_exponent);
        m.mass[w.w_dof + e] -= loss * beam_translational_mass(he, w.spec.linear_mass);
        m.mass[w.w_dof + e + 1] -= loss * beam_translational_mass(he, w.spec.linear_mass);
        if (lumped_rot) {
          m.mass[w.theta_dof + e] -= loss * beam_rotary_mass(he, w.spec.linear_mass);
          m.mass[w.theta_dof + e + 1] -= loss * beam_rotary_mass(he, w.spec.linear_mass);
        }
      }
      assemble_band(w, ei_factor);
    }

  // Constant load: gravity + support preloads - K y_design. At u = 0 it balances the static
  // dropper tensions exactly (that is what the design statics solved for).
  m.load = Eigen::VectorXd::Zero(dof);
  for (const Wire& w : m.wires)
    for (int i = 0; i < w.nodes(); ++i) m.load[w.w_dof + i] -= g * m.mass[w.w_dof + i];
  for (const SupportSpring& sp : m.springs) m.load[sp.dof] += sp.static_force;
  for (const Wire& w : m.wires) {
    const int n = w.nodes();
    std::vector<double> scratch(n);
    Wire full = w;  // with explicit rotations so that K acts on the design slopes too
    Eigen::VectorXd yfull = Eigen::VectorXd::Zero(2 * n), ffull = Eigen::VectorXd::Zero(2 * n);
    full.w_dof = 0;
    full.theta_dof = n;
    for (int i = 0; i < n; ++i) {
      yfull[i] = w.height[i];
      yfull[n + i] = w.slope[i];
    }
    wire_elastic_force(full, yfull.data(), ffull.data(), scratch.data());
    for (int i = 0; i < n; ++i) m.load[w.w_dof + i] += ffull[i];
  }
  for (int i = 0; i < dof; ++i)
    if (fixed[i]) m.load[i] = 0.0;
  apply_imperfections(scene, m, fixed);

  // Pantographs: unit-less references are set by the initial statics in the Simulation.
  int max_nodes = 2;
  double hmin = 1e9;
  for (const Wire& w : m.wires)
    for (int e = 0; e + 1 < w.nodes(); ++e) hmin = std::min(hmin, w.x[e + 1] - w.x[e]);
  if (m.rub_length > 0.0) max_nodes = static_cast<int>(std::ceil(m.rub_length / hmin)) + 3;
  m.max_contact_nodes = max_nodes;
  for (Pantograph& p : m.pantographs)
    if (!p.moving_force) {  // a moving force set in code may keep masses it does not use (no DOFs)
      for (int i = 0; i < p.masses_count(); ++i) m.mass[p.first_dof + i] = p.masses[i];
      for (const Head& h : p.heads) m.mass[h.dof] = h.mass;
    }

  m.inv_mass = Eigen::VectorXd::Zero(dof);
  for (int i = 0; i < dof; ++i) {
    if (fixed[i]) continue;
    if (!(m.mass[i] > 0.0))
      throw SceneError("model: DOF " + std::to_string(i) + " has no mass; check linear_mass and masses");
    m.inv_mass[i] = 1.0 / m.mass[i];
  }
  m.wave_speed = 1e300;
  for (int wi : m.contact_wires)
    m.wave_speed = std::min(m.wave_speed, std::sqrt(m.wires[wi].spec.tension / m.wires[wi].spec.linear_mass));
  if (const std::string w = speed_warning(m, scene.train_speed); !w.empty()) m.warnings.push_back(w);
  for (std::size_t i = 1; i < m.support_x.size(); ++i)
    m.longest_span = std::max(m.longest_span, m.support_x[i] - m.support_x[i - 1]);
  // Droppers and supports in line order, for the moving window to find its own by bisection.
  for (std::size_t k = 0; k < m.droppers.size(); ++k) m.dropper_order.push_back(static_cast<int>(k));
  std::stable_sort(m.dropper_order.begin(), m.dropper_order.end(),
                   [&](int a, int b) { return m.droppers[a].x < m.droppers[b].x; });
  for (int k : m.dropper_order) m.dropper_order_x.push_back(m.droppers[k].x);
  for (std::size_t k = 0; k < m.springs.size(); ++k) m.spring_order.push_back(static_cast<int>(k));
  std::stable_sort(m.spring_order.begin(), m.spring_order.end(), [&](int a, int b) { return m.springs[a].x < m.springs[b].x; });
  for (int k : m.spring_order) m.spring_order_x.push_back(m.springs[k].x);

  // Train travel: by default from the rearmost collector at the line start to the foremost at
  // the line end.
  double lead = 0.0, rear = 0.0;
  collector_extent(scene, &lead, &rear);
  m.train_start = scene.train_start ? *scene.train_start : -rear;
  m.train_end = scene.train_end ? *scene.train_end : m.line_length - lead;
  if (m.endless) {
    check_endless_block(m);
    if (m.train_end < endless_front)
      throw SceneError("train.end: " + fmt(m.train_end) + " m is behind the start of the pass (train front at " +
                       fmt(endless_front + 0.0) + " m)");
  } else {
    // Every collector starts and ends on the line: the statics (eq. 23) need each pantograph
    // pressed against a wire or held by its own springs at a design height under the wire.
    const double lo = 0.0 - rear, hi = m.line_length - lead;
    if (lo > hi + 1e-9)
      throw SceneError("pantographs: the collectors span " + fmt(lead - rear) + " m from the foremost to the rearmost, more than the line (" +
                       fmt(m.line_length) + " m); allowed: pantograph positions within the line length");
    if (scene.train_start && (m.train_start < lo - 1e-9 || m.train_start > hi + 1e-9))
      throw SceneError("scene field 'train.start' = " + fmt(m.train_start) + ": allowed [" + fmt(lo) + ", " + fmt(hi) +
                       "] m (the train front where every collector is on the line, 0-" + fmt(m.line_length) + " m)");
    if (scene.train_end && m.train_end > hi + 1e-9)
      throw SceneError("scene field 'train.end' = " + fmt(m.train_end) + ": allowed at most " + fmt(hi) +
                       " m (the foremost collector, " + fmt(lead) + " m ahead of the front, stays on the line)");
    if (m.train_end < m.train_start)
      throw SceneError("scene field 'train.end' = " + fmt(m.train_end) + ": allowed >= train.start (" + fmt(m.train_start) + " m)");
    // Every pantograph passes through some of the analysis section, or its statistics are empty.
    double x0 = 0.0, x1 = 0.0;
      x0 = m.support_x[scene.analysis_first()];
    x1 = m.support_x[scene.analysis_last()];
    for (const PantographSpec& p : scene.pantographs) {
      if (m.train_end - p.position < x0)
        throw SceneError("scene field 'train.end' = " + fmt(m.train_end) + ": pantograph '" + p.name +
                         "' would stop before the analysis section " + fmt(x0) + "-" + fmt(x1) +
                         " m (output.analysis_spans); allowed >= " + fmt(x0 + p.position) + " m");
      if (m.train_start - p.position > x1)
        throw SceneError("scene field 'train.start' = " + fmt(m.train_start) + ": pantograph '" + p.name +
                         "' would start after the analysis section " + fmt(x0) + "-" + fmt(x1) +
                         " m (output.analysis_spans); allowed <= " + fmt(x1 + p.position) + " m");
    }
  }

  // Initial pantograph references (eq. 23) and the stability limit (validation.md section 5).
  set_pantograph_references(m);
  if (!options.stability) {
    m.dt = m.dt_critical = scene.numerics.dt ? *scene.numerics.dt : 1e-4;
    return m;
  }
  if (scene.numerics.windowed() &&
      (scene.numerics.integrator != Integrator::kExplicit || scene.numerics.rotary_inertia != RotaryInertia::kCondensed))
    throw SceneError("numerics.window: needs numerics.integrator explicit with rotary_inertia condensed (the window "
                     "integrates node ranges of the condensed band)");
  if (scene.numerics.damping == DampingStep::kCentred) {
    // The centred step solves each whole wire's band with the rotations condensed, for u + beta v.
    std::string why;
    if (scene.numerics.integrator != Integrator::kExplicit) why = "numerics.integrator explicit";
    else if (scene.numerics.rotary_inertia != RotaryInertia::kCondensed) why = "numerics.rotary_inertia condensed";
    else if (scene.numerics.windowed()) why = "no numerics.window (nor an endless line): it solves whole wires";
    else if (scene.lateral()) why = "a 2-D line (no stagger, curve or wind): the lateral plane steps with half_step";
    else if (!(m.beta > 0.0)) why = "damping.beta > 0 (it solves for u + beta v; with beta 0 half_step has the same limit)";
    if (!why.empty()) throw SceneError("numerics.damping = 'centred': needs " + why + "; allowed otherwise: half_step");
  }
  if (scene.numerics.integrator == Integrator::kImplicit) {
    // Newmark average acceleration is unconditionally stable for the linear part, and nothing is
    // taken explicitly: slack droppers and contacts are rank-1 corrections of the factorised
    // matrix. dt is a matter of accuracy only (auto: 1 ms, bench/speed_accuracy).
    m.omega_max = 0.0;
    m.dt_critical = std::numeric_limits<double>::infinity();
    m.dt = scene.numerics.dt ? *scene.numerics.dt : 1e-3;
    m.implicit = newmark_matrix(m, m.dt);
    return m;
  }
  compute_stability_limit(m);
  if (scene.numerics.dt) {
    if (*scene.numerics.dt > m.dt_critical)
      throw SceneError("numerics.dt = " + fmt(*scene.numerics.dt) + " s: above the explicit stability limit " +
                       fmt(m.dt_critical) + " s of this model (omega_max " + fmt(m.omega_max) +
                       " rad/s); use dt <= " + fmt(m.dt_critical) + " or dt: auto");
    m.dt = *scene.numerics.dt;
  } else {
    m.dt = scene.numerics.safety_factor * m.dt_critical;
  }
  return m;
}

}  // namespace

Model build_model(const Scene& scene, const BuildOptions& options) {
  Model m = build_model_unchecked(scene, options);
  build_wire_packs(m);
  if (!options.stability) return m;
  if (scene.numerics.damping == DampingStep::kCentred) {
    if (m.wire_packs.empty())  // (condensed rotations on every wire node give packs)
      throw SceneError("numerics.damping = 'centred': needs the wires' rotations condensed; allowed otherwise: half_step");
    if (scene.numerics.dt && *scene.numerics.dt > kCentredMaxSafetyFactor * m.dt_critical)
      throw SceneError("numerics.dt = " + fmt(*scene.numerics.dt) + " s: with numerics.damping centred at most " +
                       fmt(kCentredMaxSafetyFactor) + " of the stability estimate " + fmt(m.dt_critical) + " s, dt <= " +
                       fmt(kCentredMaxSafetyFactor * m.dt_critical) + " (the estimate is not a bound for that step; see numerics.safety_factor)");
    factor_centred_damping(m);
  }
  // The statistics filter runs at the step rate: a cutoff at or above its Nyquist frequency would
  // be no filter at all (lowpass_zero_phase returns the input unchanged).
  const double nyquist = 0.5 / m.dt;
  if (!(scene.output.filter_cutoff < nyquist))
    throw SceneError("scene field 'output.filter_cutoff' = " + fmt(scene.output.filter_cutoff) + ": allowed below " +
                     fmt(nyquist) + " Hz, the Nyquist frequency of the time step (dt " + fmt(m.dt) + " s)");
  if (scene.lateral()) m.lateral = build_lateral(m);  // the 3-D line; nothing built for a 2-D scene
  return m;
}

double model_memory_limit_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return 8.0 * (1ull << 30);  // unknown: assume a small 16 GiB machine
  return 0.5 * static_cast<double>(pages) * static_cast<double>(page);
}

double estimate_model_bytes(const Scene& scene) {
  double nodes = 0.0;
  const double h = scene.numerics.element_length;
  for (const SectionSpec& sec : scene.sections) {
    double droppers = 0.0;
    if (sec.droppers)
      for (const auto& span : sec.droppers->positions) droppers += static_cast<double>(span.size());
    const double per_wire = std::ceil(sec.length() / h) + droppers + static_cast<double>(sec.spans.size()) + 1.0;
    const double wires = sec.contact_wire_count + (sec.messenger ? 1 : 0);
    nodes += wires * per_wire;
  }
  return kModelBytesPerNode * nodes + estimate_wind_field_bytes(scene);
}

double estimate_wind_field_bytes(const Scene& scene) {
  // The turbulent wind's series (wind_field.hpp): a finite line's every point, once in the model; an
  // endless line's block, in the pass's initial state and its running state.
  if (!scene.wind || !scene.wind->turbulence) return 0.0;
  return (scene.endless ? 2.0 : 1.0) * wind_field_bytes_estimate(*scene.wind, scene.line_length());
}

void check_model_memory(const Scene& scene) {
  const double need = estimate_model_bytes(scene), limit = model_memory_limit_bytes();
  if (need > limit) {
    std::ostringstream s;
    s.precision(3);
    const double wind = estimate_wind_field_bytes(scene);
    s << "scene: the model would need about " << need / (1ull << 30) << " GiB (" << scene.line_length() / 1000.0
      << " km of line in " << scene.numerics.element_length << " m elements";
    if (wind > 0.0)
      s << ", " << wind / (1ull << 30) << " GiB of it the turbulent wind's " << wind_field_points(scene)
        << " points, wind.turbulence.spacing " << scene.wind->turbulence->spacing << " m apart";
    s << "), more than the limit of " << limit / (1ull << 30) << " GiB (half of this machine's memory); ";
    if (wind > 0.5 * need)
      s << "use a longer wind.turbulence.spacing or a lower wind.turbulence.max_frequency";
    else
      s << "use a longer numerics.element_length, fewer or shorter spans (line.span_count, line.span_length), or "
           "line.endless with numerics.window";
    throw SceneError(s.str());
  }
}

double pass_step_count(const Model& m) {
  const double distance = m.train_end - m.train_start - (m.endless ? m.initial_line_offset : 0.0);
  const double v = m.scene.train_speed;
  if (!(v > 0.0)) return std::numeric_limits<double>::infinity();
  return std::max(0.0, distance) / v / m.dt;
}

}  // namespace catenary_sim
