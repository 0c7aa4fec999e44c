#include "util/format.hpp"
#include "catenary_sim/core/model/lateral.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

#include "catenary_sim/core/model/beam.hpp"
#include "catenary_sim/core/engine/state.hpp"
#include "model/normal_errors.hpp"
#include "engine/window.hpp"
#include "engine/wire_lanes.hpp"

namespace catenary_sim {
namespace {

// Share of the turbulent field's sample time (1 / (4 max_frequency)) between refreshes of the
// wind on the nodes: 0.01 s at 5 Hz, whose hold costs the field sinc^2(f 0.01 s), 0.8 % at 5 Hz.
constexpr double kWindUpdate = 0.2;

// Moving window: nodes from each cut inward that take the static force of the elements left out.
// The window's condensed stiffness differs from the line's only through the rotation at the cut,
// whose influence on K_theta_theta^-1 falls by about off-diagonal / diagonal (0.2-0.3 at 0.1-1 m
// elements of the reference wires) per element: after 32 nodes by under 1e-16.
constexpr int kCutLayer = 32;

// Index of the support at station xs in Model::support_x (supports shared by an overlap's two
// sections are one support along the line).
int line_support(const Model& m, double xs) {
  const auto it = std::lower_bound(m.support_x.begin(), m.support_x.end(), xs - 1e-6);
  return static_cast<int>(std::min<std::ptrdiff_t>(it - m.support_x.begin(), m.support_x.size() - 1));
}

// `support`: the support's index along the line (on an endless line, its block index plus the
// spans of the block's initial offset; the block moves by whole patterns, so that stays right).
double stagger_at(const Scene& s, bool contact, long support) {
  if (!s.stagger) return 0.0;
  const StaggerSpec& st = *s.stagger;
  const std::vector<double>& p = contact || st.messenger.empty() ? st.contact_wire : st.messenger;
  const long n = static_cast<long>(p.size());
  return st.at(p, static_cast<std::size_t>(((support % n) + n) % n));
}

// f -= K_lateral z over all wires, springs and pendulums (pendulum stiffness from `tension`, per
// dropper, or the static tension when null). theta: scratch of the longest wire's nodes.
void elastic_force(const Model& m, const LateralModel& lat, const double* tension, const double* z, double* f,
                   double* theta) {
  for (const Wire& w : lat.wires) wire_elastic_force(w, z, f, theta);
  for (const LateralSpring& sp : lat.springs) f[sp.dof] -= sp.stiffness * z[sp.dof];
  for (const LateralPendulum& p : lat.pendulums) {
    const double s = tension ? tension[p.dropper] : m.droppers[p.dropper].static_tension;
    const double k = std::max(0.0, s) * p.inv_length;
    const double d = k * (z[p.messenger] - z[p.contact]);
    f[p.contact] += d;
    f[p.messenger] -= d;
  }
}

// Highest eigenfrequency of M^-1 K on the free nodes by power iteration (the bound the explicit
// step must respect); 5 % added for the iteration's shortfall.
double lateral_omega_max(const Model& m, const LateralModel& lat) {
  const int n = lat.n;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n), y(n);
  std::vector<double> theta(n);
  for (int i = 0; i < n; ++i) x[i] = lat.inv_mass[i] > 0.0 ? ((i * 7919) % 13 + 1.0) : 0.0;
  double lambda = 0.0;
  for (int it = 0; it < 300; ++it) {
    const double nx = x.norm();
    if (!(nx > 0.0)) break;
    x /= nx;
    y.setZero();
    elastic_force(m, lat, nullptr, x.data(), y.data(), theta.data());
    for (int i = 0; i < n; ++i) y[i] = -y[i] * lat.inv_mass[i];
    lambda = x.dot(y);
    x = y;
  }
  return 1.05 * std::sqrt(std::max(0.0, lambda));
}

// The fused step's planes: per vertical pack (Model::wire_packs, wires on the same stations side
// by side), the lateral plane's load, alpha m, 1/m and wind drag coefficient in the pack's layout
// (PackSweep::plane); and the point nodes.
void build_lateral_packs(const Model& m, LateralModel& lat) {
  lat.planes.clear();
  lat.point_nodes.clear();
  lat.sweep_force_at.clear();
  if (m.wire_packs.empty()) return;  // the vertical step is not fused: neither is this one
  for (const WireLanes& p : m.wire_packs) {
    const int L = p.lanes;
    std::vector<double> plane(static_cast<std::size_t>(p.nodes) * kPlaneValues * L, 0.0);
    for (int k = 0; k < L; ++k) {
      const Wire& w = lat.wires[p.wire[k]];
      if (w.nodes() != p.nodes) {  // (never: the lateral wires are the vertical ones' copies)
        lat.planes.clear();
        return;
      }
      for (int i = 0; i < p.nodes; ++i) {
        double* c = plane.data() + static_cast<std::size_t>(i) * kPlaneValues * L + k;
        c[kPlaneLoad * L] = lat.load[w.w_dof + i];
        c[kPlaneDamping * L] = m.alpha * lat.mass[w.w_dof + i];
        c[kPlaneInvMass * L] = lat.inv_mass[w.w_dof + i];
        c[kPlaneDrag * L] = lat.windy ? lat.wind_coefficient[w.w_dof + i] : 0.0;
      }
    }
    lat.planes.push_back(std::move(plane));
  }
  // The band force of lateral node i of wire wi lies where the vertical sweep leaves that of the
  // wire's vertical node i.
  lat.sweep_force_at.assign(lat.n, 0);
  for (std::size_t wi = 0; wi < lat.wires.size(); ++wi)
    for (int i = 0; i < lat.wires[wi].nodes(); ++i)
      lat.sweep_force_at[lat.wires[wi].w_dof + i] = m.dof_sweep_force[m.wires[wi].w_dof + i];
  std::vector<char> listed(lat.n, 0);
  auto add = [&](int i) {
    if (listed[i]) return;
    listed[i] = 1;
    lat.point_nodes.push_back(i);
  };
  for (const LateralSpring& sp : lat.springs) add(sp.dof);
  for (const LateralPendulum& p : lat.pendulums) {
    add(p.contact);
    add(p.messenger);
  }
}

}  // namespace

void solve_lateral_statics(const Model& m, const LateralModel& lat, bool with_wind, Eigen::VectorXd* y_out,
                           std::vector<double>* force_on_support) {
  // Full system with the rotations as unknowns: y_i at i, theta_i at n + i. Rigid nodes are
  // eliminated (their rows become y_i = stagger); the unconstrained matrix gives the reactions.
  const int n = lat.n, N = 2 * n;
  Eigen::VectorXd F = Eigen::VectorXd::Zero(N), fixed_value = Eigen::VectorXd::Zero(n);
  std::vector<bool> fixed(n, false);
  for (int i = 0; i < n; ++i) F[i] = lat.load[i];
  if (with_wind && lat.windy)
    for (int i = 0; i < n; ++i) {
      const double vn = lat.wind_speed * lat.wind_normal[i];
      F[i] += lat.wind_coefficient[i] * vn * std::fabs(vn);
    }
  for (const LateralSupport& s : lat.supports)
    if (s.rigid) {
      const int i = lat.wires[s.wire].w_dof + s.node;
      fixed[i] = true;
      fixed_value[i] = s.stagger;
    }
  std::vector<Eigen::Triplet<double>> full, reduced;
  Eigen::VectorXd Fr = F;
  auto add = [&](int i, int j, double v) {
    full.emplace_back(i, j, v);
    const bool fi = i < n && fixed[i], fj = j < n && fixed[j];
    if (fi) return;
    if (fj) Fr[i] -= v * fixed_value[j];
    else reduced.emplace_back(i, j, v);
  };
  for (const Wire& w : lat.wires) {
    const int o = w.w_dof, nn = w.nodes();
    for (int i = 0; i < nn; ++i) {
      const int a = o + i, t = n + o + i;
      add(a, a, w.d_ww[i]);
      add(a, t, w.d_wt[i]);
      add(t, a, w.d_wt[i]);
      add(t, t, w.d_tt[i]);
    }
    for (int e = 0; e + 1 < nn; ++e) {
      const int a = o + e, b = o + e + 1, ta = n + a, tb = n + b;
      add(a, b, w.e_ww[e]);
      add(b, a, w.e_ww[e]);
      add(a, tb, w.e_wt[e]);
      add(tb, a, w.e_wt[e]);
      add(ta, b, w.e_tw[e]);
      add(b, ta, w.e_tw[e]);
      add(ta, tb, w.e_tt[e]);
      add(tb, ta, w.e_tt[e]);
    }
  }
  for (const LateralSpring& sp : lat.springs) add(sp.dof, sp.dof, sp.stiffness);
  for (const LateralPendulum& p : lat.pendulums) {
    const double k = std::max(0.0, m.droppers[p.dropper].static_tension) * p.inv_length;
    add(p.contact, p.contact, k);
    add(p.messenger, p.messenger, k);
    add(p.contact, p.messenger, -k);
    add(p.messenger, p.contact, -k);
  }
  for (int i = 0; i < n; ++i)
    if (fixed[i]) {
      reduced.emplace_back(i, i, 1.0);
      Fr[i] = fixed_value[i];
    }
  Eigen::SparseMatrix<double> K(N, N), Kf(N, N);
  K.setFromTriplets(reduced.begin(), reduced.end());
  Kf.setFromTriplets(full.begin(), full.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(K);
  if (solver.info() != Eigen::Success)
    throw SceneError("scene: the lateral statics has no solution: a wire is free to move sideways (check stagger.steady_arm_stiffness and stagger.messenger_support_stiffness)");
  const Eigen::VectorXd x = solver.solve(Fr);
  if (solver.info() != Eigen::Success || !x.allFinite())
    throw SceneError("scene: the lateral statics has no solution (a wire free to move sideways)");
  *y_out = x.head(n);
  if (force_on_support) {
    // The wire's force on each support: the load at its node less the elastic force K x there
    // (for a spring support, the spring's share k (y - stagger) is the wire's push on it).
    const Eigen::VectorXd r = F - Kf * x;
    force_on_support->assign(lat.supports.size(), 0.0);
    std::vector<double> spring_term(n, 0.0);  // k (y - stagger): r holds it with the opposite sign
    for (const LateralSpring& sp : lat.springs) spring_term[sp.dof] = sp.stiffness * (x[sp.dof] - sp.anchor);
    for (std::size_t k = 0; k < lat.supports.size(); ++k) {
      const LateralSupport& s = lat.supports[k];
      const int i = lat.wires[s.wire].w_dof + s.node;
      const double v = r[i] + spring_term[i];
      (*force_on_support)[k] = v;
    }
  }
}

// The built line's stagger errors per line support (imperfections.stagger_std or stagger_errors):
// normal errors from a generator of their own, so adding them leaves every other draw as it was.
std::vector<double> stagger_errors(const Model& m) {
  const ImperfectionSpec& im = m.scene.imperfections;
  const std::size_t n = m.support_x.size();
  if (!im.stagger_errors.empty()) {
    if (im.stagger_errors.size() != n)
      throw SceneError("scene field 'imperfections.stagger_errors' = (" + std::to_string(im.stagger_errors.size()) +
                       " values): one per support in line order (" + std::to_string(n) + ")");
    return im.stagger_errors;
  }
  std::vector<double> e(n, 0.0);
  if (!(im.stagger_std > 0.0)) return e;
  // SplitMix64 of the study seed: a stream apart from the dropper and steady-arm draws of `seed`.
  std::uint64_t z = im.seed + 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  NormalErrors gen(im.stagger_seed ? *im.stagger_seed : z ^ (z >> 31));
  for (double& v : e) v = gen.next(im.stagger_std);
  return e;
}

double gust_lead_time(const Scene& sc) {
  if (!sc.wind || !sc.wind->turbulence || !(sc.wind->speed > 0.0) || !sc.numerics.windowed()) return 0.0;
  if (sc.numerics.gust_lead) return *sc.numerics.gust_lead;
  if (!sc.endless) return 0.0;
  // A span entering the window at rest lacks the resonant motion the gusts build up; what is left
  // of that start decays as exp(-sigma t), so after 2 / sigma its share of the rms is some 5 % of
  // the resonant part's, and the rms itself is short by a fraction of a percent (BENCHMARKS.md).
  const WindSpec& w = *sc.wind;
  const double normal = w.speed * std::fabs(std::sin(w.direction * M_PI / 180.0 - sc.alignment.heading(0.0)));
  auto sigma = [&](const WireDragSpec& d, double linear_mass) {
    return w.air_density * d.drag_coefficient * d.diameter * normal / (2.0 * linear_mass) + 0.5 * sc.rayleigh_alpha;
  };
  double slowest = sigma(w.contact_wire, sc.contact_wire.linear_mass);
  if (sc.messenger) slowest = std::min(slowest, sigma(w.messenger, sc.messenger->linear_mass));
  return slowest > kGustLeadDecays / kAutoGustLeadMax ? kGustLeadDecays / slowest : kAutoGustLeadMax;
}

std::shared_ptr<const LateralModel> build_lateral(const Model& m) {
  const Scene& sc = m.scene;
  const std::vector<double> stagger_error = stagger_errors(m);
  auto lat = std::make_shared<LateralModel>();
  int off = 0;
  for (const Wire& w : m.wires) {
    Wire l = w;
    l.w_dof = off;
    l.theta_dof = -1;  // massless rotations, condensed (assemble_band always factorises K_tt)
    off += w.nodes();
    lat->wires.push_back(std::move(l));
  }
  const int n = lat->n = off;
  lat->mass = Eigen::VectorXd::Zero(n);
  lat->inv_mass = Eigen::VectorXd::Zero(n);
  lat->load = Eigen::VectorXd::Zero(n);
  lat->node_span.assign(n, -1);
  // Blow-off per span along a finite line; an endless line's block spans are not the line's.
  lat->spans = m.endless ? 0 : static_cast<int>(m.support_x.size()) - 1;
  const long support_offset = m.endless ? std::lround(m.initial_line_offset / m.endless_span) : 0;
  const std::optional<double> arm_k = sc.stagger ? sc.stagger->steady_arm_stiffness : std::nullopt;
  const std::optional<double> msup_k = sc.stagger ? sc.stagger->messenger_support_stiffness : std::nullopt;
  std::vector<bool> fixed(n, false);
  for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
    const Wire& w = m.wires[wi];
    const Wire& l = lat->wires[wi];
    const int nn = w.nodes();
    for (int i = 0; i < nn; ++i) {
      const int a = l.w_dof + i;
      // Translational mass as in the vertical plane (wire, clamps, support masses); the vertical
      // plane leaves it 0 where it holds a node rigidly, so the wire's own share is used there.
      double mi = m.mass[w.w_dof + i];
      if (!(mi > 0.0)) {
        mi = 0.0;
        if (i > 0) mi += beam_translational_mass(w.x[i] - w.x[i - 1], w.spec.linear_mass);
        if (i + 1 < nn) mi += beam_translational_mass(w.x[i + 1] - w.x[i], w.spec.linear_mass);
      }
      lat->mass[a] = mi;
      // The curve in the track's frame: a load T kappa per metre (lateral.hpp).
      const double h = 0.5 * ((i + 1 < nn ? w.x[i + 1] : w.x[i]) - (i > 0 ? w.x[i - 1] : w.x[i]));
      lat->load[a] += w.spec.tension * sc.alignment.curvature(w.x[i]) * h;
      lat->node_x.push_back(w.x[i]);
      if (w.is_contact_wire && !m.endless) {
        const auto it = std::upper_bound(m.support_x.begin(), m.support_x.end(), w.x[i]);
        lat->node_span[a] = std::clamp(static_cast<int>(it - m.support_x.begin()) - 1, 0, lat->spans - 1);
      }
    }
    const int ns = static_cast<int>(w.support_nodes.size());
    for (int k = 0; k < ns; ++k) {
      LateralSupport s;
      s.wire = static_cast<int>(wi);
      s.node = w.support_nodes[k];
      s.x = w.x[s.node];
      s.line_support = line_support(m, s.x);
      s.stagger = stagger_at(sc, w.is_contact_wire, s.line_support + support_offset) +
                  (w.is_contact_wire ? stagger_error[s.line_support] : 0.0);  // (no errors on an endless line)
      s.anchor = k == 0 || k == ns - 1;
      const std::optional<double>& spring = w.is_contact_wire ? arm_k : msup_k;
      s.rigid = s.anchor || !spring;
      const int a = l.w_dof + s.node;
      if (s.rigid) {
        fixed[a] = true;
      } else {
        lat->springs.push_back(LateralSpring{a, *spring, s.stagger});
        lat->load[a] += *spring * s.stagger;
      }
      lat->supports.push_back(s);
    }
  }
  for (int i = 0; i < n; ++i) lat->inv_mass[i] = fixed[i] ? 0.0 : 1.0 / lat->mass[i];
  // Droppers as pendulums between their two nodes.
  auto lateral_dof = [&](int vertical) {
    for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
      const Wire& w = m.wires[wi];
      if (vertical >= w.w_dof && vertical < w.w_dof + w.nodes()) return lat->wires[wi].w_dof + vertical - w.w_dof;
    }
    return -1;
  };
  for (std::size_t k = 0; k < m.droppers.size(); ++k) {
    const Dropper& d = m.droppers[k];
    LateralPendulum p;
    p.contact = lateral_dof(d.contact_dof);
    p.messenger = lateral_dof(d.messenger_dof);
    p.dropper = static_cast<int>(k);
    // A dropper shorter than 5 cm would be a lateral clamp, not a pendulum: held at 5 cm.
    p.inv_length = 1.0 / std::max(0.05, d.length);
    p.half_inv_length = 0.5 * p.inv_length;  // the same l as the pendulum: one potential (lateral.hpp)
    lat->pendulums.push_back(p);
  }
  // Wind: the normal component of the mean wind on each node's wire, following the track's heading.
  if (sc.wind) {
    const WindSpec& ws = *sc.wind;
    lat->windy = ws.speed > 0.0;
    lat->wind_speed = ws.speed;
    lat->wind_coefficient = Eigen::VectorXd::Zero(n);
    lat->wind_normal = Eigen::VectorXd::Zero(n);
    const double phi = ws.direction * M_PI / 180.0;
    double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo;
    for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
      const Wire& w = m.wires[wi];
      const WireDragSpec& d = w.is_contact_wire ? ws.contact_wire : ws.messenger;
      const int nn = w.nodes();
      for (int i = 0; i < nn; ++i) {
        const int a = lat->wires[wi].w_dof + i;
        const double h = 0.5 * ((i + 1 < nn ? w.x[i + 1] : w.x[i]) - (i > 0 ? w.x[i - 1] : w.x[i]));
        lat->wind_coefficient[a] = 0.5 * ws.air_density * d.drag_coefficient * d.diameter * h;
        lat->wind_normal[a] = std::sin(phi - sc.alignment.heading(w.x[i]));
      }
      x_lo = std::min(x_lo, w.x.front());
      x_hi = std::max(x_hi, w.x.back());
    }
    if (ws.turbulence) {
      const double start = m.train_start + (m.endless ? m.initial_line_offset : 0.0);  // along the line
      const double duration = sc.train_speed > 0.0 ? (m.train_end - start) / sc.train_speed : 600.0;
      if (m.endless) {
        // The field along the line the block passes over (stations = block x + line offset),
        // looked up at each refresh (lateral_step), so the wind a span feels is its own; the
        // state holds the block's points only and generates those ahead as the block moves.
        const double block = x_hi - x_lo;
        lat->field_block_end = x_hi;
        x_lo += m.initial_line_offset;
        x_hi = std::max(x_lo + block, m.train_end + block);
        lat->field = make_wind_field(ws, x_lo, x_hi, duration, block);
      } else {
        lat->field = make_wind_field(ws, x_lo, x_hi, duration);
        lat->field_values.reset(lat->field);
      }
      lat->field_index.assign(n, 0);
      lat->field_weight.assign(n, 0.0);
      for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
        const Wire& w = m.wires[wi];
        for (int i = 0; i < w.nodes(); ++i) {
          const int a = lat->wires[wi].w_dof + i;
          int j = 0;
          lat->field.locate(w.x[i], &j, &lat->field_weight[a]);
          lat->field_index[a] = j;
          if (lat->field_runs.empty() || lat->field_runs.back().point != j || lat->field_runs.back().end != a)
            lat->field_runs.push_back(LateralModel::FieldRun{a, a, j});
          lat->field_runs.back().end = a + 1;
        }
      }
    }
  }
  lat->windowed = sc.numerics.windowed() && (m.endless || lat->field.empty() || sc.numerics.gust_lead.has_value());
  lat->gust_lead = lat->windowed ? gust_lead_time(sc) : 0.0;
  const PantographHeadSpec& head = sc.pantograph_head;
  lat->half_working_width = 0.5 * head.working_width;
  lat->half_horn_width = 0.5 * head.horn_width;

  // Statics: without wind (the design in plan, and the pull-off), then under the mean wind.
  std::vector<double> calm_force, wind_force;
  solve_lateral_statics(m, *lat, false, &lat->calm, &calm_force);
  solve_lateral_statics(m, *lat, true, &lat->initial, &wind_force);
  // The built lean under the mean wind: the droppers' reference (lateral.hpp), so that the pass
  // starts with every dropper at its design stretch.
  for (LateralPendulum& p : lat->pendulums) {
    const double dy0 = lat->initial[p.messenger] - lat->initial[p.contact];
    p.lean0_sq = dy0 * dy0;
  }
  for (std::size_t k = 0; k < lat->supports.size(); ++k) {
    lat->supports[k].pull_off = calm_force[k];
    lat->supports[k].pull_off_wind = wind_force[k];
  }
  lat->static_blow_off.assign(std::max(0, lat->spans), 0.0);
  for (int i = 0; i < n; ++i)
    if (lat->node_span[i] >= 0)
      lat->static_blow_off[lat->node_span[i]] =
          std::max(lat->static_blow_off[lat->node_span[i]], std::fabs(lat->initial[i] - lat->calm[i]));

  // Stability: the lateral plane's own limit (Rayleigh damping reduces it as in the vertical
  // plane); it takes as many substeps of the vertical dt as it needs.
  lat->omega_max = lateral_omega_max(m, *lat);
  const double xi = 0.5 * (m.alpha / std::max(lat->omega_max, 1e-9) + m.beta * lat->omega_max);
  const double dt_crit = lat->omega_max > 0.0 ? 2.0 / lat->omega_max * (std::sqrt(1.0 + xi * xi) - xi)
                                               : std::numeric_limits<double>::infinity();
  lat->substeps = std::max(1, static_cast<int>(std::ceil(m.dt / (0.9 * dt_crit))));
  if (lat->substeps > 1000)
    throw SceneError("scene field 'stagger.steady_arm_stiffness': the lateral plane's stability limit (" + fmt(dt_crit) +
                     " s) would need " + std::to_string(lat->substeps) + " substeps of dt " + fmt(m.dt) +
                     " s; allowed at most 1000: lower the lateral support stiffnesses");
  lat->dt = m.dt / lat->substeps;
  build_lateral_packs(m, *lat);
  // For the moving window: the wires' elastic force in the static state, and the springs in line order.
  lat->static_elastic_force = Eigen::VectorXd::Zero(n);
  {
    std::vector<double> theta(n);
    for (const Wire& w : lat->wires) wire_elastic_force(w, lat->initial.data(), lat->static_elastic_force.data(), theta.data());
  }
  lat->spring_order.resize(lat->springs.size());
  std::iota(lat->spring_order.begin(), lat->spring_order.end(), 0);
  std::stable_sort(lat->spring_order.begin(), lat->spring_order.end(), [&](int a, int b) {
    return lat->node_x[lat->springs[a].dof] < lat->node_x[lat->springs[b].dof];
  });
  for (int k : lat->spring_order) lat->spring_order_x.push_back(lat->node_x[lat->springs[k].dof]);
  return lat;
}

void update_head_wind(const Model& m, State& s, const WindFieldBuffer* field, const double* field_points) {
  const LateralModel& lat = *m.lateral;
  if (!lat.windy) return;
  const double phi = m.scene.wind->direction * M_PI / 180.0;
  const WindField& fd = lat.field;
  for (std::size_t p = 0; p < m.pantographs.size(); ++p) {
    const double x = s.front - m.pantographs[p].position + s.line_offset;  // station along the line
    double along_wind = lat.wind_speed;  // the along-wind speed U + u' (wind_field.hpp)
    if (field && field_points && !fd.empty()) along_wind += field->at(fd, field_points, x);
    // Its component along the track, against the direction of travel (+x).
    s.head_wind[p] = -along_wind * std::cos(phi - m.scene.alignment.heading(x));
  }
}

LateralState make_lateral_state(const Model& m) {
  const LateralModel& lat = *m.lateral;
  LateralState s;
  s.y = lat.initial;
  s.v = Eigen::VectorXd::Zero(lat.n);
  s.f = Eigen::VectorXd::Zero(lat.n);
  s.z = Eigen::VectorXd::Zero(lat.n);
  s.y_next = s.y;
  s.v_next = Eigen::VectorXd::Zero(lat.n);
  s.accel = Eigen::VectorXd::Zero(lat.n);
  s.sweep.assign(2 * kSweepRecord * m.sweep_size, 0.0);  // (both planes' records when joint)
  int longest = 0;
  for (const Wire& w : lat.wires) longest = std::max(longest, w.nodes());
  s.theta.assign(longest, 0.0);
  s.wind_points.assign(std::max(0, lat.field.held), 0.0);
  if (m.endless) s.wind_field.reset(lat.field);  // (nothing for a steady wind)
  if (lat.windy) s.wind_speed = lat.wind_speed * lat.wind_normal;  // the mean wind until the field's first refresh
  s.weight_node.assign(m.max_contact_nodes, 0);
  s.weight.assign(m.max_contact_nodes, 0.0);
  s.contact_lateral.assign(m.collectors.size() * m.contact_wires.size(), std::nan(""));
  s.collector_lateral.assign(m.collectors.size(), std::nan(""));
  s.pantograph_lateral.assign(m.pantographs.size(), 0.0);
  s.off_strip.assign(m.collectors.size(), 0);
  s.events.reserve(kMaxDewirementEvents);
  s.dropper_stretch.assign(m.droppers.size(), 0.0);
  s.lean_weight.assign(m.droppers.size(), 1.0);
  for (const LateralPendulum& p : lat.pendulums) s.dropper_stretch[p.dropper] = lean_stretch(p, s.y.data());  // 0: y is initial
  s.window.resize(lat.wires.size());
  for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) {
    s.window[wi].tt_lower.assign(lat.wires[wi].nodes(), 0.0);
    s.window[wi].tt_inv_pivot.assign(lat.wires[wi].nodes(), 0.0);
  }
  if (lat.windowed && !lat.planes.empty()) s.sweep_factors.assign(2 * m.sweep_size, 0.0);
  s.window_springs.assign(lat.springs.size(), 0);
  s.window_droppers.assign(lat.pendulums.size(), 0);
  s.cut_node.assign(2 * kCutLayer * m.wires.size(), 0);
  s.cut_force.assign(s.cut_node.size(), 0.0);
  s.window_points.assign(s.cut_node.size() + lat.springs.size() + 2 * lat.pendulums.size(), 0);
  return s;
}

namespace {

// Contact points across the strips and dewirement (a change of the off-strip flag). Returns true
// when a collector left the working width in this call.
bool contact_points(const Model& m, State& s, bool record) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  const PantographHeadSpec& head = m.scene.pantograph_head;
  const double sway = head.sway(s.time);  // the contact point on the strip is wire minus pantograph
  const std::size_t nw = m.contact_wires.size();
  bool left = false;
  for (std::size_t pi = 0; pi < m.pantographs.size(); ++pi) {
    const Pantograph& p = m.pantographs[pi];
    ls.pantograph_lateral[pi] = sway;
    const double x_ref = s.front - p.position;
    for (int ci : p.collectors) {
      const double xc = x_ref + m.collectors[ci].offset;
      double best_force = 0.0;
      int running = -1;
      for (std::size_t wk = 0; wk < nw; ++wk) {
        const Wire& w = lat.wires[m.contact_wires[wk]];
        const int cnt = contact_weights(w, m.rub_length, xc, ls.weight_node.data(), ls.weight.data());
        double y = 0.0;
        for (int a = 0; a < cnt; ++a) y += ls.weight[a] * ls.y[w.w_dof + ls.weight_node[a]];
        ls.contact_lateral[ci * nw + wk] = cnt ? y - sway : std::nan("");
        const double fc = s.contact_force[ci * nw + wk];
        if (cnt && fc > best_force) {
          best_force = fc;
          running = static_cast<int>(wk);
        }
      }
      if (running < 0) lowest_design_height(m, xc, &running);  // not touching: the wire it meets first
      const double yc = running >= 0 ? ls.contact_lateral[ci * nw + running] : std::nan("");
      ls.collector_lateral[ci] = yc;
      const bool off = std::fabs(yc) > m.collectors[ci].half_working_width;  // false for NaN
      if (off && !ls.off_strip[ci] && record) {
        left = true;
        ++ls.events_total;
        if (ls.events.size() < kMaxDewirementEvents)
          ls.events.push_back(DewirementEvent{s.time, xc + s.line_offset, static_cast<int>(pi), ci, yc});
      }
      ls.off_strip[ci] = off;
    }
  }
  return left;
}

}  // namespace

void lateral_observe(const Model& m, State& s) {
  if (m.lateral) contact_points(m, s, false);
}

namespace {

// The turbulent field's values: a finite line's in the model, an endless line's in its state.
const WindFieldBuffer& field_values(const Model& m, const State& s) {
  return m.endless ? s.lateral.wind_field : m.lateral->field_values;
}

// An endless line's field generated up to the point after the block's last node at the line
// offset `offset` (WindField::held keeps the block's first node's point).
void extend_endless_field(const Model& m, State& s, double offset) {
  const WindField& fd = m.lateral->field;
  s.lateral.wind_field.extend_to(fd, static_cast<int>(std::floor((m.lateral->field_block_end + offset - fd.x0) / fd.dx)) + 1);
}

// The wind's speed normal to nodes i0..i1-1 of the field's last sample (LateralState::wind_points;
// zero before the first refresh: the mean wind).
void refresh_wind(const Model& m, State& s, int i0, int i1) {
  const LateralModel& lat = *m.lateral;
  const double* wp = s.lateral.wind_points.data();
  const double U = lat.wind_speed;
  const double* sn = lat.wind_normal.data();
  double* W = s.lateral.wind_speed.data();
  if (m.endless) {
    // The block's nodes at their stations along the line now, from the points held from `first`
    // (which cover the block: extend_endless_field).
    const WindField& fd = lat.field;
    const int first = s.lateral.wind_field.first(), top = std::max(first, s.lateral.wind_field.end() - 2);
    for (int i = i0; i < i1; ++i) {
      int j = 0;
      double a = 0.0;
      fd.locate(lat.node_x[i] + s.line_offset, &j, &a);
      j = std::clamp(j, first, top) - first;
      W[i] = (U + (1.0 - a) * wp[j] + a * wp[j + 1]) * sn[i];
    }
  } else {
    // Per run of nodes between two field points (the same operations as per node).
    const std::vector<LateralModel::FieldRun>& runs = lat.field_runs;
    std::size_t k = std::upper_bound(runs.begin(), runs.end(), i0,
                                     [](int i, const LateralModel::FieldRun& r) { return i < r.begin; }) -
                    runs.begin();
    k = k > 0 ? k - 1 : 0;
    const double* weight = lat.field_weight.data();
    for (; k < runs.size() && runs[k].begin < i1; ++k) {
      const double p0 = wp[runs[k].point], p1 = wp[runs[k].point + 1];
      const int b = std::max(i0, runs[k].begin), e = std::min(i1, runs[k].end);
      for (int i = b; i < e; ++i) {
        const double a = weight[i];
        W[i] = (U + (1.0 - a) * p0 + a * p1) * sn[i];
      }
    }
  }
}

// Calls body(i0, i1) on the lateral DOFs stepped: each wire's window, or the whole line.
template <class Body>
void over_stepped(const Model& m, const State& s, bool windowed, Body&& body) {
  if (!windowed) {
    body(0, m.lateral->n);
    return;
  }
  const LateralState& ls = s.lateral;
  for (std::size_t wi = 0; wi < m.lateral->wires.size(); ++wi)
    if (ls.window[wi].hi >= ls.window[wi].lo) {
      const int o = m.lateral->wires[wi].w_dof;
      body(o + ls.window[wi].lo, o + ls.window[wi].hi + 1);
    }
}

// The turbulent wind on the nodes stepped at time t, if a refresh is due: the wind's speed normal
// to each node's wire, W = (U + u') sin(angle), is refreshed every kWindUpdate of the field's
// sample time (it is linear between samples 0.1 s apart at the default 5 Hz); the drag on the
// moving wire is taken every step.
void refresh_wind_if_due(const Model& m, State& s, double t, bool windowed) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  if (!lat.windy || lat.field.empty() || !(t + 1e-12 >= ls.next_wind_update)) return;
  ls.next_wind_update = t + kWindUpdate * lat.field.dt;
  ls.wind_time = t;
  if (m.endless) extend_endless_field(m, s, s.line_offset);
  field_values(m, s).at_time(lat.field, t, ls.wind_points.data());
  over_stepped(m, s, windowed, [&](int i0, int i1) { refresh_wind(m, s, i0, i1); });  // (only where stepped)
}

// The moving window (numerics.window): the lateral plane steps the vertical plane's window
// (State::window, which update_window moved before this step; the lateral waves run at the same
// sqrt(T/rhoA), so the same window holds their echoes) and, in a turbulent wind, a lead of
// LateralModel::gust_lead seconds of travel further ahead, so that a span has felt the gusts that
// long when the pantograph reaches it. When it moved, the nodes that left it return to the static
// state under the mean wind at rest (as the vertical plane's to u = 0), the nodes that entered
// get the wind of the last refresh, and the lists are rebuilt: springs and pendulums in the
// window, and at each cut the static force of the elements left out (-K initial of the whole line
// less the window's), so that the static state stays at rest in the window as outside it. Costs
// what the window holds (bisection for the springs and droppers), not the line.
void sync_window(const Model& m, State& s) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  const std::vector<double>& sx = m.support_x;
  const int first = s.window_first_support;
  int last = s.window_last_support;
  if (first >= 0 && lat.gust_lead > 0.0) {
    const double hi_x = sx[last] + lat.gust_lead * std::fabs(s.speed);  // the lead, snapped outward to a support
    last = static_cast<int>(std::lower_bound(sx.begin(), sx.end(), hi_x - 1e-6) - sx.begin());
    last = std::min(last, static_cast<int>(sx.size()) - 1);
  }
  if (first == ls.window_first_support && last == ls.window_last_support && !ls.window_dirty) return;
  ls.window_dirty = false;
  ls.window_first_support = first;
  ls.window_last_support = last;
  const bool turbulent = lat.windy && !lat.field.empty();
  double* y = ls.y.data();
  double* v = ls.v.data();
  double* f = ls.f.data();
  ls.cut_count = 0;
  ls.window_fused = !lat.planes.empty();
  const double xa = first >= 0 ? sx[first] : 0.0, xb = first >= 0 ? sx[last] : -1.0;
  for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) {
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
    if (turbulent)
      for (int i = lo; i <= hi; ++i)
        if (i < old_lo || i > old_hi) refresh_wind(m, s, o + i, o + i + 1);
    if (hi < lo) continue;
    if (hi == lo) ls.window_fused = false;  // (as the vertical step: the sweep needs two nodes)
    if (!ww.cut_lo && !ww.cut_hi) continue;
    for (int i = lo; i <= hi; ++i) f[o + i] = 0.0;
    wire_elastic_force_window(w, ww, lat.initial.data(), f, ls.theta.data());
    auto add_cut = [&](int i) {
      ls.cut_node[ls.cut_count] = o + i;
      ls.cut_force[ls.cut_count++] = lat.static_elastic_force[o + i] - f[o + i];
    };
    const int lo_end = ww.cut_lo ? std::min(hi, lo + kCutLayer - 1) : lo - 1;
    for (int i = lo; i <= lo_end; ++i) add_cut(i);
    if (ww.cut_hi)
      for (int i = std::max(lo_end + 1, hi - kCutLayer + 1); i <= hi; ++i) add_cut(i);
  }
  for (const WireLanes& p : m.wire_packs)
    if (p.lanes == 2 && (ls.window[p.wire[0]].lo != ls.window[p.wire[1]].lo || ls.window[p.wire[0]].hi != ls.window[p.wire[1]].hi))
      ls.window_fused = false;
  if (ls.window_fused) interleave_window_factors(m.wire_packs, ls.window, ls.sweep_factors.data());
  // Springs and pendulums (droppers) between the window's end supports whose nodes it holds.
  auto inside = [&](int dof) { return in_windows(lat.wires, ls.window, dof); };
  ls.window_spring_count = ls.window_dropper_count = 0;
  if (first >= 0) {
    ls.window_spring_count = select_between(
        lat.spring_order, lat.spring_order_x, xa, xb, [&](int k) { return inside(lat.springs[k].dof); },
        ls.window_springs.data());
    ls.window_dropper_count = select_between(
        m.dropper_order, m.dropper_order_x, xa, xb,
        [&](int k) { return inside(lat.pendulums[k].contact) && inside(lat.pendulums[k].messenger); },
        ls.window_droppers.data());
  }
  // The fused step's nodes with point forces: the cut layers, springs, pendulums.
  int q = 0;
  for (int j = 0; j < ls.cut_count; ++j) ls.window_points[q++] = ls.cut_node[j];
  for (int j = 0; j < ls.window_spring_count; ++j) ls.window_points[q++] = lat.springs[ls.window_springs[j]].dof;
  for (int j = 0; j < ls.window_dropper_count; ++j) {
    const LateralPendulum& p = lat.pendulums[ls.window_droppers[j]];
    ls.window_points[q++] = p.contact;
    ls.window_points[q++] = p.messenger;
  }
  ls.window_point_count = q;
}

// The window's own point forces, first after the band: the cut layers' static force and, at the
// cuts, a dashpot of the wire's impedance sqrt(T rhoA) that lets the outgoing waves leave (the
// vertical plane's, add_wire_point_forces).
void add_window_forces(const Model& m, const State& s, const double* v, double* f) {
  const LateralModel& lat = *m.lateral;
  const LateralState& ls = s.lateral;
  for (int j = 0; j < ls.cut_count; ++j) f[ls.cut_node[j]] += ls.cut_force[j];
  for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) {
    const WireWindow& ww = ls.window[wi];
    if (ww.hi < ww.lo) continue;
    const Wire& w = lat.wires[wi];
    const double c = std::sqrt(w.spec.tension * w.spec.linear_mass);
    if (ww.cut_lo) f[w.w_dof + ww.lo] -= c * v[w.w_dof + ww.lo];
    if (ww.cut_hi) f[w.w_dof + ww.hi] -= c * v[w.w_dof + ww.hi];
  }
}

}  // namespace

bool setup_lateral_sweep(const Model& m, State& s, std::size_t pack, bool windowed, PackSweep& a) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  const WireLanes& p = m.wire_packs[pack];
  if (!setup_pack_sweep(p, lat.wires, windowed ? &ls.window : nullptr, ls.sweep_factors.data(), s.sweep.data(), ls.y.data(),
                        ls.v.data(), ls.y_next.data(), ls.v_next.data(), ls.accel.data(), a))
    return false;
  // (the records in the vertical step's scratch, State::sweep; sweep_pack_pair puts them elsewhere)
  a.plane = lat.planes[pack].data();
  // The wind's drag is taken in the sweep (PackSweep::wind), on the velocity it reads anyway.
  for (int k = 0; k < p.lanes; ++k) a.wind[k] = lat.windy ? ls.wind_speed.data() + lat.wires[p.wire[k]].w_dof : nullptr;
  a.beta = m.beta;
  a.dt = lat.dt;
  a.limit = m.scene.numerics.divergence_limit;
  return true;
}

namespace {

// The springs (steady arms, messenger supports) and the droppers' pendulums on f, at
// z = y + beta v (`z_at`), over the window's lists or the whole line: the pendulums at the
// droppers' tension now with their lean's share (two-way coupling, lateral.hpp), 0 when slack, and
// each lean summed into dropper_stretch for the next vertical step. The fused and the generic
// step share it, so they do the same operations.
template <class ZAt>
void add_springs_and_pendulums(const Model& m, State& s, bool windowed, const double* y, ZAt z_at, double* f) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  const int n_springs = windowed ? ls.window_spring_count : static_cast<int>(lat.springs.size());
  for (int j = 0; j < n_springs; ++j) {
    const LateralSpring& sp = lat.springs[windowed ? ls.window_springs[j] : j];
    f[sp.dof] -= sp.stiffness * z_at(sp.dof);
  }
  const double* u = s.u.data();
  double* stretch = ls.dropper_stretch.data();
  const double* w = ls.lean_weight.data();
  const int n_pendulums = windowed ? ls.window_dropper_count : static_cast<int>(lat.pendulums.size());
  for (int j = 0; j < n_pendulums; ++j) {
    const LateralPendulum& p = lat.pendulums[windowed ? ls.window_droppers[j] : j];
    const Dropper& d = m.droppers[p.dropper];
    const double lean = lean_stretch(p, y);
    stretch[p.dropper] += lean;
    const double tension = d.static_tension + d.stiffness * ((u[d.messenger_dof] - u[d.contact_dof]) + lean * w[p.dropper]);
    const double k = std::max(0.0, tension) * p.inv_length;
    const double df = k * (z_at(p.messenger) - z_at(p.contact));
    f[p.contact] += df;
    f[p.messenger] -= df;
  }
}

// One lateral substep fused as the vertical plane's (wire_lanes.hpp): per pack one sweep pair for
// z, the condensed rotations, the band force with the load, damping and the wind's drag, and the
// update; then the nodes with point forces (steady arms and
// messenger supports as springs, droppers as pendulums) are updated again with theirs, in the
// generic step's order. The new values go to y_next, v_next and are swapped in when all are
// inside the divergence limit (else the state keeps the last good substep and this returns true).
// Windowed: over the window's nodes (the vertical plane's factors of it), the window's forces
// first among the point forces, the new values copied back in the window.
bool fused_substep(const Model& m, State& s, bool windowed) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  const double h = lat.dt, beta = m.beta, limit = m.scene.numerics.divergence_limit;
  const double* y = ls.y.data();
  const double* v = ls.v.data();
  double* yn = ls.y_next.data();
  double* vn = ls.v_next.data();
  double* acc = ls.accel.data();
  // The band sweeps: taken along by this step's vertical sweeps (step_both_planes), else here.
  const int joined = ls.joined;  // (its records then in the joint layout: joint_record_index)
  bool outside = joined && ls.joined_outside;
  if (!joined)
    for (std::size_t pk = 0; pk < m.wire_packs.size(); ++pk) {
      PackSweep a;
      if (setup_lateral_sweep(m, s, pk, windowed, a)) outside |= sweep_pack(a);
    }
  ls.joined = false;
  // Point forces on the band forces the sweep left in its records, as the generic step adds them.
  double* f = ls.f.data();
  const double* rec = joined ? ls.sweep.data() : s.sweep.data();
  const int* at = lat.sweep_force_at.data();
  const int* points = windowed ? ls.window_points.data() : lat.point_nodes.data();
  const int np = windowed ? ls.window_point_count : static_cast<int>(lat.point_nodes.size());
  for (int q = 0; q < np; ++q) f[points[q]] = rec[joint_record_index(at[points[q]], joined, true)];
  if (windowed) add_window_forces(m, s, v, f);
  add_springs_and_pendulums(m, s, windowed, y, [y, v, beta](int i) { return y[i] + beta * v[i]; }, f);
  const double* im = lat.inv_mass.data();
  for (int q = 0; q < np; ++q) {
    const int i = points[q];
    acc[i] = im[i] * f[i];
    vn[i] = v[i] + h * acc[i];
    yn[i] = y[i] + h * vn[i];
    outside |= !(std::fabs(yn[i]) <= limit);
  }
  if (outside) {  // the sweeps' flag is a hint (they saw the point nodes before their forces)
    int bad = 0;
    over_stepped(m, s, windowed, [&](int i0, int i1) {
      for (int i = i0; i < i1; ++i) bad |= !(std::fabs(yn[i]) <= limit);
    });
    if (bad) return true;
  }
  if (windowed) {  // outside the window the new buffers hold nothing current: copy the window back
    double* yw = ls.y.data();
    double* vw = ls.v.data();
    over_stepped(m, s, true, [&](int i0, int i1) {
      for (int i = i0; i < i1; ++i) {
        yw[i] = yn[i];
        vw[i] = vn[i];
      }
    });
    return false;
  }
  ls.y.swap(ls.y_next);  // O(1)
  ls.v.swap(ls.v_next);
  return false;
}

}  // namespace

StepStatus lateral_step(const Model& m, State& s) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  const double h = lat.dt, beta = m.beta, alpha = m.alpha;
  const double* load = lat.load.data();
  const double* mass = lat.mass.data();
  const double* inv_mass = lat.inv_mass.data();
  double* y = ls.y.data();
  double* v = ls.v.data();
  double* f = ls.f.data();
  double* z = ls.z.data();
  const double limit = m.scene.numerics.divergence_limit;
  const double t0 = s.time - m.dt;  // the vertical step has already moved the clock on
  // The droppers' lean over this step's substeps (all at this u), for the next vertical step.
  for (double& e : ls.dropper_stretch) e = 0.0;
  if (m.scene.numerics.windowed()) {
    // Outside the vertical plane's window the droppers' ends are held vertically (the window does
    // not move them), so a lean there would load the dropper with k delta against rigid wires,
    // where the free line gives way (delta / (1/k + f_c + f_m), some 1/300 of it): the lean acts on
    // the tension only inside the window, as in the vertical step.
    for (double& x : ls.lean_weight) x = 0.0;
    for (int j = 0; j < s.window_dropper_count; ++j) ls.lean_weight[s.window_droppers[j]] = 1.0;
  }
  const bool windowed = lat.windowed;
  if (windowed) sync_window(m, s);
  for (int sub = 0; sub < lat.substeps; ++sub) {
    refresh_wind_if_due(m, s, t0 + sub * h, windowed);
    if (!lat.planes.empty() && (!windowed || ls.window_fused)) {
      if (fused_substep(m, s, windowed)) {
        ls.diverged = true;
        s.status = StepStatus::kDiverged;
        return s.status;
      }
      continue;
    }
    // The generic step (what the fused one computes, bit for bit: test_lateral).
    y = ls.y.data();
    v = ls.v.data();
    over_stepped(m, s, windowed, [&](int i0, int i1) {
      if (lat.windy) {
        const double* cw = lat.wind_coefficient.data();
        const double* W = ls.wind_speed.data();
        for (int i = i0; i < i1; ++i) {
          z[i] = y[i] + beta * v[i];
          const double vn = W[i] - v[i];  // relative to the moving wire: aerodynamic damping
          f[i] = load[i] - alpha * mass[i] * v[i] + cw[i] * vn * std::fabs(vn);
        }
      } else {
        for (int i = i0; i < i1; ++i) {
          z[i] = y[i] + beta * v[i];
          f[i] = load[i] - alpha * mass[i] * v[i];
        }
      }
    });
    if (windowed) {
      for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) wire_elastic_force_window(lat.wires[wi], ls.window[wi], z, f, ls.theta.data());
      add_window_forces(m, s, v, f);
    } else {
      for (const Wire& w : lat.wires) wire_elastic_force(w, z, f, ls.theta.data());
    }
    add_springs_and_pendulums(m, s, windowed, y, [z](int i) { return z[i]; }, f);
    int out = 0;  // an integer OR vectorises where a max over doubles (NaN rules) does not
    over_stepped(m, s, windowed, [&](int i0, int i1) {
      for (int i = i0; i < i1; ++i) {
        const double a = inv_mass[i] * f[i];  // eq. 20-21, in the fused sweep's order
        v[i] += h * a;
        y[i] += h * v[i];
        out |= !(std::fabs(y[i]) <= limit);  // also NaN
      }
    });
    if (out) {
      ls.diverged = true;
      s.status = StepStatus::kDiverged;
      return s.status;
    }
  }
  const double per_substep = 1.0 / lat.substeps;
  for (double& e : ls.dropper_stretch) e *= per_substep;
  update_head_wind(m, s, &field_values(m, s), ls.wind_points.data());
  const bool left = contact_points(m, s, true);
  if (left && m.scene.pantograph_head.on_dewirement == DewirementAction::kStop) {
    ls.dewired_stop = true;
    s.status = StepStatus::kDewired;
  }
  return s.status;
}

StepStatus step_both_planes(const Model& m, State& s) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  // Both planes sweep every node of the same packs: no window, one lateral step a vertical one,
  // both fused, and the step will be taken (not the pass's end).
  bool two_wire_packs = true;  // (sweep_pack_pair's four lanes)
  for (const WireLanes& p : m.wire_packs) two_wire_packs &= p.lanes == 2;
  ls.join = !lat.planes.empty() && two_wire_packs && lat.substeps == 1 && !m.scene.numerics.windowed() &&
            s.status == StepStatus::kOk && s.front + s.line_offset < m.train_end && !ls.dropper_stretch.empty();
  // The lateral step's wind is that of the step's start, t0 as lateral_step computes it (after
  // the vertical step's s.time += dt), refreshed now for the sweep (lateral_step then finds it
  // done: the same values, once).
  if (ls.join) refresh_wind_if_due(m, s, (s.time + m.dt) - m.dt, false);
  const StepStatus st = step(m, s);
  ls.join = false;
  if (st != StepStatus::kOk) {
    ls.joined = false;
    return st;
  }
  return lateral_step(m, s);
}

void shift_lateral_block(const Model& m, State& s) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  const bool windowed = lat.windowed;  // (an endless line always is)
  for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) {
    const Wire& w = lat.wires[wi];
    const int ns = m.endless_shift_spans * m.span_nodes[wi], o = w.w_dof, nn = w.nodes();
    // The nodes stepped: the window (outside it they are in the static state), as the vertical
    // plane moves its window (shift_endless_block).
    const int lo = windowed ? ls.window[wi].lo : 0, hi = windowed ? ls.window[wi].hi : nn - 1;
    if (hi < lo) continue;
    // Upward, the destination below the source. Held nodes (supports at the stagger, which
    // repeats with the block's move) keep their value. The wind moves along: a node's station
    // along the line is the one the node ns above had.
    for (int i = std::max(lo, ns); i <= hi; ++i) {
      if (lat.inv_mass[o + i - ns] > 0.0) {
        ls.y[o + i - ns] = ls.y[o + i];
        ls.v[o + i - ns] = ls.v[o + i];
      }
      if (lat.windy) ls.wind_speed[o + i - ns] = ls.wind_speed[o + i];
    }
    // The nodes the move leaves (the spans entering at the far end of the block or window) are
    // at rest in the static state under the mean wind, as the vertical plane's at u = 0.
    for (int i = std::max({0, lo, hi - ns + 1}); i <= hi; ++i)
      if (lat.inv_mass[o + i] > 0.0) {
        ls.y[o + i] = lat.initial[o + i];
        ls.v[o + i] = 0.0;
      }
    if (windowed) {
      ls.window[wi].lo = std::max(0, lo - ns);
      ls.window[wi].hi = hi - ns;
    }
  }
  ls.window_dirty = true;  // the lists and factors hold the old DOFs (the node ranges already match)
  set_dropper_stretch(m, s);  // the droppers' lean moved with the block
  if (lat.windy && !lat.field.empty()) {
    // The spans entering ahead take the wind of the last refresh at their stations (sync_window):
    // the field generated that far (the caller moves line_offset on by the shift after this), and
    // the held points' values at that refresh.
    extend_endless_field(m, s, s.line_offset + m.endless_shift_spans * m.endless_span);
    ls.wind_field.at_time(lat.field, ls.wind_time, ls.wind_points.data());
  }
}

void set_dropper_stretch(const Model& m, State& s) {
  for (const LateralPendulum& p : m.lateral->pendulums)
    s.lateral.dropper_stretch[p.dropper] = lean_stretch(p, s.lateral.y.data());
}

namespace {

// V(e) = S0 e + k e^2 / 2 while taut, S0 + k e > 0; constant (its value at the switch) when slack.
double dropper_potential(const Dropper& d, double e) {
  if (!(d.stiffness > 0.0)) return d.static_tension * e;
  e = std::max(e, -d.static_tension / d.stiffness);
  return d.static_tension * e + 0.5 * d.stiffness * e * e;
}

// The lateral plane's energy without the droppers: kinetic, wires and supports, less the loads.
double lateral_wire_energy(const Model& m, const State& s) {
  const LateralModel& lat = *m.lateral;
  const int n = lat.n;
  Eigen::VectorXd f = Eigen::VectorXd::Zero(n);
  std::vector<double> theta(n);
  const double* y = s.lateral.y.data();
  for (const Wire& w : lat.wires) wire_elastic_force(w, y, f.data(), theta.data());  // f = -K y
  for (const LateralSpring& sp : lat.springs) f[sp.dof] -= sp.stiffness * y[sp.dof];
  double e = 0.0;
  for (int i = 0; i < n; ++i)
    e += 0.5 * lat.mass[i] * s.lateral.v[i] * s.lateral.v[i] * (lat.inv_mass[i] > 0.0) - 0.5 * y[i] * f[i] -
         lat.load[i] * y[i];
  return e;
}

}  // namespace

double lateral_energy(const Model& m, const State& s) {
  double e = lateral_wire_energy(m, s);
  const double* u = s.u.data();
  for (const LateralPendulum& p : m.lateral->pendulums) {
    const Dropper& d = m.droppers[p.dropper];
    const double ez = u[d.messenger_dof] - u[d.contact_dof];
    e += dropper_potential(d, ez + lean_stretch(p, s.lateral.y.data())) - dropper_potential(d, ez);
  }
  return e;
}

double line_energy(const Model& m, const State& s) {
  // The vertical plane: 0.5 v M v + 0.5 u K u - load . u over the wires (rotations as DOFs or
  // condensed) and their supports; the droppers' V(e) with the lean's share when 3-D.
  const int nc = m.n_catenary_dof;
  Eigen::VectorXd f = Eigen::VectorXd::Zero(m.n_dof);
  int longest = 1;
  for (const Wire& w : m.wires) longest = std::max(longest, w.nodes());
  std::vector<double> theta(longest);
  const double* u = s.u.data();
  for (const Wire& w : m.wires) wire_elastic_force(w, u, f.data(), theta.data());  // f = -K u
  for (const SupportSpring& sp : m.springs) f[sp.dof] -= sp.stiffness * u[sp.dof];
  double e = 0.0;
  for (int i = 0; i < nc; ++i)
    e += 0.5 * m.mass[i] * s.v[i] * s.v[i] * (m.inv_mass[i] > 0.0) - 0.5 * u[i] * f[i] - m.load[i] * u[i];
  for (std::size_t k = 0; k < m.droppers.size(); ++k) {
    const Dropper& d = m.droppers[k];
    e += dropper_potential(d, u[d.messenger_dof] - u[d.contact_dof]);
  }
  if (m.lateral) e += lateral_energy(m, s);
  return e;
}

}  // namespace catenary_sim
