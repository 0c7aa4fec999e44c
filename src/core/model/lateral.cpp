#include "util/format.hpp"
#include "catenary_sim/core/model/lateral.hpp"
#include "catenary_sim/core/model/stability.hpp"

#include <Eigen/LU>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <sstream>

#include "catenary_sim/core/model/beam.hpp"
#include "catenary_sim/core/model/wire_band.hpp"
#include "model/centred_factors.hpp"
#include "model/design_statics.hpp"
#include "model/normal_errors.hpp"
#include "model/selected_inverse.hpp"
#include "model/wire_packs.hpp"

namespace catenary_sim {
namespace {

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

// overlap.lateral_separation: at a support two sections share, each section's wires held s/2 to
// either side of the stagger, the ending section's (the earlier: the later one shares the support)
// to + of it for s > 0; 0 where one section alone is held. `first`, `last`: per line support, the
// lowest and highest section with a wire held there.
struct OverlapSides {
  std::vector<int> first, last;
  double half = 0.0;
  explicit OverlapSides(const Model& m) {
    if (m.scene.overlap) half = 0.5 * m.scene.overlap->lateral_separation;
    first.assign(m.support_x.size(), std::numeric_limits<int>::max());
    last.assign(m.support_x.size(), -1);
    for (const Wire& w : m.wires)
      for (int node : w.support_nodes) {
        const int j = line_support(m, w.x[node]);
        first[j] = std::min(first[j], w.section);
        last[j] = std::max(last[j], w.section);
      }
  }
  double offset(int line_support, int section) const {
    if (half == 0.0 || first[line_support] == last[line_support]) return 0.0;
    return section < last[line_support] ? half : -half;
  }
};

// f -= K_lateral z over all wires, springs, pendulums and stitch wires' clamps (pendulum
// stiffness from `tension`, per dropper, or the static tension when null). theta: scratch of the
// longest wire's nodes.
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
  for (const LateralClamp& c : lat.clamps) {
    const double d = c.stiffness * (z[c.upper] - z[c.lower]);
    f[c.lower] += d;
    f[c.upper] -= d;
  }
}

// Highest eigenfrequency of M^-1 K on the free nodes (the bound the explicit step must respect),
// as the vertical plane's (power_iteration_omega), with its 0.2 % margin for what the iteration
// has not converged.
double lateral_omega_max(const Model& m, const LateralModel& lat) {
  std::vector<double> theta(lat.n);
  const Eigen::VectorXd s = lat.inv_mass.cwiseSqrt();
  return 1.002 * power_iteration_omega(lat.n, s.data(), 3000, [&](const double* x, double* y) {
    std::fill(y, y + lat.n, 0.0);
    elastic_force(m, lat, nullptr, x, y, theta.data());  // (f -= K x)
    for (int i = 0; i < lat.n; ++i) y[i] = -y[i];
  });
}

// The fused step's planes: per vertical pack (Model::wire_packs, wires on the same stations side
// by side), the lateral plane's load, alpha m, 1/m and wind drag coefficient in the pack's layout
// (PackSweep::plane); and the point nodes.
void build_lateral_packs(const Model& m, LateralModel& lat) {
  lat.planes.clear();
  lat.point_nodes.clear();
  lat.sweep_force_at.clear();
  lat.joint_force_at.clear();
  if (!m.wire_packs) return;  // the vertical step is not fused: neither is this one
  // The fused sweep runs on the vertical packs' band: a wire bending otherwise across the track (a
  // rail's profile with its own lateral EI) takes the generic lateral step.
  for (std::size_t wi = 0; wi < lat.wires.size(); ++wi)
    if (lat.wires[wi].spec.bending_stiffness != m.wires[wi].spec.bending_stiffness) return;
  for (const WireLanes& p : m.wire_packs->packs) {
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
  // wire's vertical node i; in the joint records, the pack's lanes further on.
  lat.sweep_force_at.assign(lat.n, 0);
  lat.joint_force_at.assign(lat.n, 0);
  for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) {
    const int lanes = m.wire_packs->packs[m.wire_packs->wire_pack[wi]].lanes;
    for (int i = 0; i < lat.wires[wi].nodes(); ++i) {
      lat.sweep_force_at[lat.wires[wi].w_dof + i] = m.wire_packs->dof_sweep_force[m.wires[wi].w_dof + i];
      lat.joint_force_at[lat.wires[wi].w_dof + i] = m.wire_packs->dof_joint_force[m.wires[wi].w_dof + i] + lanes;
    }
  }
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
  for (const LateralClamp& c : lat.clamps) {
    add(c.lower);
    add(c.upper);
  }
  // A held registration and its row's nodes: the sweep may see it where the last step put it,
  // the point forces then add its move's share (add_springs_and_pendulums, lateral_step.cpp).
  for (const LateralRegistration& r : lat.registrations) {
    if (r.spring >= 0) continue;
    int lo = 0, hi = 0;
    registration_reach(r, lat.wires[r.wire].nodes(), &lo, &hi);
    for (int i = lo; i <= hi; ++i) add(lat.wires[r.wire].w_dof + i);
  }
}


// The wire's force on each support: the load at its node less the elastic force K x there (for a
// spring support, the spring's share k (y - stagger) is the wire's push on it).
void support_forces(const LateralModel& lat, const Eigen::VectorXd& F, const Eigen::SparseMatrix<double>& Kf,
                    const Eigen::VectorXd& x, std::vector<double>* force_on_support) {
  const int n = lat.n;
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

// The lateral wires (the vertical ones' band, or a rail profile's own across the track; rotations
// condensed), their masses, the curve's load and the supports in plan: rigid at the stagger, or
// springs pulling toward it.
void add_wires_and_supports(const Model& m, LateralModel* lat) {
  const Scene& sc = m.scene;
  const std::vector<double> stagger_error = stagger_errors(m);
  int off = 0;
  for (const Wire& w : m.wires) {
    Wire l = w;
    l.w_dof = off;
    l.theta_dof = -1;  // massless rotations, condensed (assemble_band always factorises K_tt)
    // A rail's profile bends across the track with its own EI where the scene gives it (the round
    // wires alike both ways); the plane then has a band of its own (no fused sweep on the vertical
    // packs' band: build_lateral_packs). Its transition pieces soften it across the track in the
    // same proportion.
    const std::optional<double>& lateral_ei = sc.sections[w.section].rail_lateral_bending_stiffness;
    if (lateral_ei && *lateral_ei != w.spec.bending_stiffness) {
      l.spec.bending_stiffness = *lateral_ei;
      assemble_band(l, transition_piece_factors(sc, w));
    }
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
  const OverlapSides overlap(m);
  const double half_width = 0.5 * sc.pantograph_head.working_width;
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
      // Under bridles the contact wire passes its intermediate supports free: their clamps hold it.
      if (w.is_contact_wire && sc.sections[w.section].bridle && k > 0 && k < ns - 1) continue;
      LateralSupport s;
      s.wire = static_cast<int>(wi);
      s.node = w.support_nodes[k];
      s.x = w.x[s.node];
      s.line_support = line_support(m, s.x);
      // A compound line's auxiliary runs above the contact wire it hangs by its short hangers:
      // held in plan at the contact wire's stagger at every support (vertically it passes them
      // free, hung by its droppers), so that the hangers hang plumb and the droppers above take
      // any lean toward the messenger.
      const double apart = overlap.offset(s.line_support, w.section);
      // A bridle's middle starts at the contact wire's stagger there (register_bridles moves it).
      const bool contact_side = w.is_contact_wire || w.is_bridle;
      s.stagger = stagger_at(sc, contact_side || w.is_auxiliary_messenger, s.line_support + support_offset) +
                  (contact_side ? stagger_error[s.line_support] : 0.0) +  // (no errors on an endless line)
                  apart;
      if (contact_side && apart != 0.0 && !(std::fabs(s.stagger) < half_width))  // (a bridle's: where the wire passes)
        throw SceneError("scene field 'overlap.lateral_separation' = " + fmt(sc.overlap->lateral_separation) +
                         " m puts the contact wire of section " + std::to_string(w.section) + " at " + fmt(s.stagger) +
                         " m at the support at station " + fmt(s.x) + " m: keep it inside the pantograph head's working width, |y| < " +
                         fmt(half_width) + " m (pantograph_head.working_width / 2)");
      s.anchor = !w.is_bridle && (k == 0 || k == ns - 1);  // (a bridle's one support: its middle)
      const std::optional<double>& spring = contact_side ? arm_k : msup_k;
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
}

// The hinged steady arms' registrations (LateralRegistration): every intermediate support of a
// contact wire whose vertical spring is a hinged arm pulled to one side. Section ends (anchors)
// stay put.
void add_registrations(const Model& m, LateralModel* lat) {
  std::vector<int> arm_at(m.n_dof, -1);  // per vertical DOF: its hinged arm in Model::springs
  for (std::size_t k = 0; k < m.springs.size(); ++k)
    if (m.springs[k].hinged_arm() && m.springs[k].arm_pull_side != 0.0) arm_at[m.springs[k].dof] = static_cast<int>(k);
  // Per lateral DOF: its spring in LateralModel::springs, and the pendulums hanging there (found
  // once, not per arm: a long line has as many arms as droppers' tenths).
  std::vector<int> spring_at(lat->n, -1);
  for (std::size_t j = 0; j < lat->springs.size(); ++j) spring_at[lat->springs[j].dof] = static_cast<int>(j);
  std::vector<std::vector<int>> pendulums_at(lat->n);
  for (std::size_t j = 0; j < lat->pendulums.size(); ++j) pendulums_at[lat->pendulums[j].contact].push_back(static_cast<int>(j));
  for (const LateralSupport& sup : lat->supports) {
    const Wire& w = m.wires[sup.wire];
    if (!w.is_contact_wire || sup.anchor) continue;
    const int vertical = w.w_dof + sup.node, k = arm_at[vertical];
    if (k < 0) continue;
    const SupportSpring& sp = m.springs[k];
    LateralRegistration r;
    r.dof = lat->wires[sup.wire].w_dof + sup.node;
    r.vertical = vertical;
    r.spring = spring_at[r.dof];
    r.wire = sup.wire;
    r.node = sup.node;
    r.length = sp.arm_length;
    r.sin0 = std::sin(sp.arm_inclination);
    r.cos0 = std::cos(sp.arm_inclination);
    r.side = sp.arm_pull_side;
    r.pendulums = pendulums_at[r.dof];
    lat->registrations.push_back(r);
  }
}

// The lateral DOF of a wire node's vertical DOF (-1: not a wire node).
int lateral_dof_of(const Model& m, const LateralModel& lat, int vertical) {
  const int wi = wire_holding(m, vertical);
  return wi < 0 ? -1 : lat.wires[wi].w_dof + vertical - m.wires[wi].w_dof;
}

// The droppers as pendulums between their two nodes.
void add_pendulums(const Model& m, LateralModel* lat) {
  auto lateral_dof = [&](int vertical) { return lateral_dof_of(m, *lat, vertical); };
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
}

// The stitch wires' clamps in plan: the vertical plane's springs (Model::clamps) between the same
// two nodes.
void add_clamps(const Model& m, LateralModel* lat) {
  for (const WireClamp& c : m.clamps)
    lat->clamps.push_back(
        LateralClamp{lateral_dof_of(m, *lat, c.upper_dof), lateral_dof_of(m, *lat, c.lower_dof), c.stiffness});
}

// Wind: the normal component of the mean wind on each node's wire, following the track's heading,
// and the turbulent field along the line.
void add_wind(const Model& m, const WindSpec& ws, LateralModel* lat) {
  const Scene& sc = m.scene;
  const int n = lat->n;
  lat->windy = ws.speed > 0.0;
  lat->wind_speed = ws.speed;
  lat->wind_coefficient = Eigen::VectorXd::Zero(n);
  lat->wind_normal = Eigen::VectorXd::Zero(n);
  const double phi = ws.direction * M_PI / 180.0;
  double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo;
  for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
    const Wire& w = m.wires[wi];
    const WireDragSpec& d = sc.sections[w.section].rigid ? ws.conductor_rail
                            : w.is_contact_wire          ? ws.contact_wire
                            : w.is_bridle                ? ws.bridle
                            : w.is_clamped_wire          ? ws.stitch_wire
                            : w.is_auxiliary_messenger   ? ws.auxiliary_messenger
                                                         : ws.messenger;
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

// Statics: without wind (the design in plan, and the pull-off), then under the mean wind.
void set_static_states(const Model& m, LateralModel* lat) {
  const int n = lat->n;
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
}

// Stability: the lateral plane's own limit (Rayleigh damping reduces it as in the vertical
// plane); it takes as many substeps of the vertical dt as it needs.
void set_substeps(const Model& m, LateralModel* lat) {
  lat->omega_max = lateral_omega_max(m, *lat);
  // The wind's drag on v_{n-1/2} is explicit damping, 2 c_w |W - v| per node (its derivative in
  // v): a node's rate 2 c_w U / m at the wind's normal speed, gusts to six standard deviations
  // included, taken as mass-proportional damping with the band (it binds only on a wire of well
  // under a gram per metre: 0.3 1/s on the reference contact wire at 30 m/s).
  double drag_rate = 0.0;
  if (lat->windy) {
    const WindSpec& ws = *m.scene.wind;
    const double gusts = ws.speed * (1.0 + 6.0 * (ws.turbulence ? ws.turbulence->intensity : 0.0));
    for (int i = 0; i < lat->n; ++i)
      drag_rate = std::max(drag_rate, 2.0 * lat->wind_coefficient[i] * gusts * lat->inv_mass[i]);
  }
  // The centred step takes the wires' Rayleigh damping implicitly: its limit is the undamped one.
  const bool centred = m.scene.numerics.damping == DampingStep::kCentred;
  double dt_crit = !(lat->omega_max > 0.0) ? std::numeric_limits<double>::infinity()
                   : centred                 ? critical_time_step(lat->omega_max, drag_rate, 0.0)
                                             : critical_time_step(lat->omega_max, m.alpha + drag_rate, m.beta);
  if (centred) {
    // The centred step takes the wires' band at the step's middle, but the support springs and
    // clamps act as point forces on y + beta v: their beta k is explicit damping on their nodes
    // (as in the vertical plane: compute_stability_limit); a stiff lateral spring (5e7 N/m on a
    // 1 kg bracket: 2 / (beta k / m) = 0.4 ms) binds here, not in the band.
    PointDampingLimit points(lat->inv_mass);
    for (const LateralSpring& sp : lat->springs) points.ground(sp.dof, sp.stiffness, m.beta * sp.stiffness);
    for (const LateralClamp& c : lat->clamps) points.link(c.upper, c.lower, c.stiffness, m.beta * c.stiffness);
    dt_crit = std::min(dt_crit, points.time_step());
  }
  lat->substeps = std::max(1, static_cast<int>(std::ceil(m.dt / (0.9 * dt_crit))));
  if (lat->substeps > 1000)
    throw SceneError("scene field 'stagger.steady_arm_stiffness': the lateral plane's stability limit (" + fmt(dt_crit) +
                     " s) would need " + std::to_string(lat->substeps) + " substeps of dt " + fmt(m.dt) +
                     " s; allowed at most 1000: lower the lateral support stiffnesses");
  lat->dt = m.dt / lat->substeps;
}

// The centred damping step's factors of the lateral plane's whole wires (LateralModel::centred_*).
void factor_lateral_centred(const Model& m, LateralModel& lat) {
  const CentredPlane plane{&lat.wires, lat.mass.data(), lat.inv_mass.data(), centred_shift(m, lat.dt)};
  lat.centred_v_ratio = (2.0 / lat.dt) / plane.shift;
  lat.centred_held.clear();
  for (int i = 0; i < lat.n; ++i)
    if (lat.inv_mass[i] == 0.0) lat.centred_held.push_back(i);
  std::vector<double> scratch;
  for (const WireLanes& p : packs_of(m)) {
    const int L = p.lanes;
    std::vector<double> twin(p.centred_twin.size(), 0.0), single(p.centred_single.size(), 0.0);
    scratch.assign(static_cast<std::size_t>(p.nodes) * kCdValues, 0.0);
    for (int lane = 0; lane < L; ++lane)
      factor_centred_range(plane, p, lane, 0, p.nodes - 1, nullptr, scratch.data(), twin.data(), single.data());
    lat.centred_twin.push_back(std::move(twin));
    lat.centred_single.push_back(std::move(single));
  }
  // Both planes of a lone wire in one solve (LateralModel::centred_joint_twin): the lanes share
  // dt, so one substep a step; the lateral forces must be ready before the vertical step; both
  // planes over the whole wire (no window in either, and so no gust lead). Without wind nothing
  // else loads such a plane, and lateral_step leaves it at rest or steps a moved one alone.
  if (!lat.windy || lat.substeps != 1 || m.scene.numerics.windowed() || !lat.pendulums.empty() ||
      !lat.registrations.empty())
    return;
  const CentredPlane vertical{&m.wires, m.mass.data(), m.inv_mass.data(), centred_shift(m, m.dt)};
  for (const WireLanes& p : packs_of(m)) {
    std::vector<double> twin, single;
    if (p.lanes == 1) {
      WireLanes both = p;  // the wire twice: lane 0 in the vertical plane, lane 1 in the lateral one
      both.lanes = 2;
      both.wire[1] = p.wire[0];
      twin.assign(2 * p.centred_twin.size(), 0.0);
      single.assign(2 * p.centred_single.size(), 0.0);
      scratch.assign(static_cast<std::size_t>(p.nodes) * kCdValues, 0.0);
      factor_centred_range(vertical, both, 0, 0, p.nodes - 1, nullptr, scratch.data(), twin.data(), single.data());
      factor_centred_range(plane, both, 1, 0, p.nodes - 1, nullptr, scratch.data(), twin.data(), single.data());
    }
    lat.centred_joint_twin.push_back(std::move(twin));
    lat.centred_joint_single.push_back(std::move(single));
  }
}

// For the moving window: the wires' elastic force in the static state, and the springs in line order.
void prepare_window(LateralModel* lat) {
  const int n = lat->n;
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
}

// The lateral plane's stiffness with the rotations as unknowns (y_i at i, theta_i at n + i):
// add(i, j, value) for every entry of the wires' bands, the support springs and the droppers as
// pendulums at their static tension, the stitch wires' clamps.
template <class Add>
void add_stiffness(const Model& m, const LateralModel& lat, Add&& add) {
  const int n = lat.n;
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
  for (const LateralClamp& c : lat.clamps) {
    add(c.lower, c.lower, c.stiffness);
    add(c.upper, c.upper, c.stiffness);
    add(c.lower, c.upper, -c.stiffness);
    add(c.upper, c.lower, -c.stiffness);
  }
}

// The lateral statics' system, factorised once for any number of load cases. The full system
// has the rotations as unknowns: y_i at i, theta_i at n + i. Rigid nodes (`fixed` per lateral DOF)
// are eliminated: their rows become y_i = their value, and their columns move to the loads; the
// unconstrained matrix (full(), kept on request) gives the reactions.
class LateralSystem {
 public:
  LateralSystem(const Model& m, const LateralModel& lat, const std::vector<bool>& fixed, bool keep_full)
      : n_(lat.n), fixed_(fixed) {
    std::vector<Eigen::Triplet<double>> full;
    factorise([&](auto&& add) { add_stiffness(m, lat, add); }, keep_full ? &full : nullptr, {});
    if (keep_full) {
      full_.resize(2 * n_, 2 * n_);
      full_.setFromTriplets(full.begin(), full.end());
    }
  }
  // From the plane's whole stiffness `full` (add_stiffness's, assembled), kept as full();
  // `also_pattern`: pairs of free rows put on the factor's pattern (as stored zeros) for the
  // entries of the inverse that inverse() gives.
  LateralSystem(Eigen::SparseMatrix<double> full, const std::vector<bool>& fixed,
                const std::vector<std::pair<int, int>>& also_pattern)
      : n_(static_cast<int>(full.rows() / 2)), fixed_(fixed), full_(std::move(full)) {
    factorise(
        [&](auto&& add) {
          for (int j = 0; j < full_.outerSize(); ++j)
            for (Eigen::SparseMatrix<double>::InnerIterator it(full_, j); it; ++it)
              add(static_cast<int>(it.row()), j, it.value());
        },
        nullptr, also_pattern);
  }
  // The displacements (2n rows) under loads F (2n rows, the rotations' 0) with the rigid nodes at
  // `fixed_value` (n rows), a column per case.
  Eigen::MatrixXd solve(const Eigen::MatrixXd& F, const Eigen::MatrixXd& fixed_value) const {
    Eigen::MatrixXd Fr = F;
    const int cases = static_cast<int>(F.cols());
    for (const Eigen::Triplet<double>& t : moved_)
      for (int c = 0; c < cases; ++c) Fr(t.row(), c) -= t.value() * fixed_value(t.col(), c);
    for (int i = 0; i < n_; ++i)
      if (fixed_[i]) Fr.row(i) = fixed_value.row(i);
    Eigen::MatrixXd x = solver_.solve(Fr);
    if (solver_.info() != Eigen::Success || !x.allFinite())
      throw SceneError("scene: the lateral statics has no solution (a wire free to move sideways)");
    return x;
  }
  const Eigen::SparseMatrix<double>& full() const { return full_; }
  // The reduced system's inverse on its factor's pattern (the held rows' are the identity's).
  SelectedInverse inverse() const { return SelectedInverse(solver_); }

 private:
  // `entries(add)` calls add(i, j, value) for each entry of the whole stiffness (`full` keeps
  // them, if given).
  template <class Entries>
  void factorise(Entries&& entries, std::vector<Eigen::Triplet<double>>* full,
                 const std::vector<std::pair<int, int>>& also_pattern) {
    const int N = 2 * n_;
    std::vector<Eigen::Triplet<double>> reduced;
    entries([&](int i, int j, double v) {
      if (full) full->emplace_back(i, j, v);
      const bool fi = i < n_ && fixed_[i], fj = j < n_ && fixed_[j];
      if (fi) return;
      if (fj) moved_.emplace_back(i, j, v);  // (in this order: the loads take them as assembled)
      else reduced.emplace_back(i, j, v);
    });
    for (int i = 0; i < n_; ++i)
      if (fixed_[i]) reduced.emplace_back(i, i, 1.0);
    for (const auto& [a, b] : also_pattern) reduced.emplace_back(std::max(a, b), std::min(a, b), 0.0);
    Eigen::SparseMatrix<double> K(N, N);
    K.setFromTriplets(reduced.begin(), reduced.end());
    solver_.compute(K);
    if (solver_.info() != Eigen::Success)
      throw SceneError("scene: the lateral statics has no solution: a wire is free to move sideways (check stagger.steady_arm_stiffness and stagger.messenger_support_stiffness)");
  }

  int n_;
  std::vector<bool> fixed_;
  std::vector<Eigen::Triplet<double>> moved_;  // the entries in the rigid nodes' columns
  Eigen::SparseMatrix<double> full_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver_;
};

// Bridles in plan: the stagger is where the contact wire passes each support, where only the
// bridle's clamps hold it, so the bridle's middle is registered beyond it, far enough that its
// arms carry the wire's pull-off (T_b (b - y_c) / a at a clamp, a the arm, y_c the clamp's
// position). The design in plan holds the middles there rigidly, at the registrations b that
// put the contact wire at its stagger at every support (plan_bridles). A lateral spring
// (stagger.steady_arm_stiffness) pulls the middle toward its registration, as a steady arm's pulls
// the wire toward its stagger.
struct BridlePlan {
  std::vector<int> held;            // per bridle: its support's index in lat.supports
  std::vector<int> middle;          // its middle's lateral DOF
  std::vector<double> target;       // the contact wire's stagger at its support
  Eigen::VectorXd registration;     // b: where its middle is held
  Eigen::VectorXd ends;             // its first and last node in plan, [2 j], [2 j + 1]
  // Bridle j's arm e (0: toward its first node) in plan and up its V, as slopes from the middle.
  double across(const Model& m, const LateralModel& lat, int j, int e) const {
    const Wire& w = m.wires[lat.supports[held[j]].wire];
    const int end = e == 0 ? 0 : w.nodes() - 1;
    return std::fabs(ends[2 * j + e] - registration[j]) / std::fabs(w.x[end] - w.x[w.support_nodes.front()]);
  }
  double up(const Model& m, const LateralModel& lat, int j, int e) const {
    const Wire& w = m.wires[lat.supports[held[j]].wire];
    return bridle_arm_rise(w, e == 0 ? 0 : w.nodes() - 1);
  }
};

BridlePlan plan_bridles(const Model& m, const LateralModel& lat) {
  BridlePlan p;
  std::vector<int> at;  // per bridle: the contact wire's lateral DOF at its support
  for (std::size_t k = 0; k < lat.supports.size(); ++k) {
    const LateralSupport& s = lat.supports[k];
    const Wire& bridle = m.wires[s.wire];
    if (!bridle.is_bridle) continue;
    const int contact = m.sections[bridle.section].wires.front();  // (a bridle holds one contact wire)
    const Wire& cw = m.wires[contact];
    p.held.push_back(static_cast<int>(k));
    const auto node = std::lower_bound(cw.x.begin(), cw.x.end(), s.x - 1e-9) - cw.x.begin();  // (a node: mesh_section)
    at.push_back(lat.wires[contact].w_dof + static_cast<int>(node));
    p.target.push_back(s.stagger);
  }
  const int nb = static_cast<int>(p.held.size());
  if (nb == 0) return p;
  const int n = lat.n, N = 2 * n;
  // One square system for the plane and the registrations together: each middle's y is an
  // unknown (its b), and its row, where its reaction would balance it, says instead that the
  // contact wire at its support is at the stagger: one sparse solve, where the plane solved once
  // per registration and then a dense system for the b would cost the square of the line's
  // length and more (the contact wire, free at its supports, ties every bridle to the next).
  // Rigid nodes' rows are y_i = their value, their columns moved to the loads, as in LateralSystem.
  std::vector<bool> rigid(n, false);
  std::vector<int> middle_of(n, -1);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(N);
  rhs.head(n) = lat.load;
  p.middle.resize(nb);
  for (int j = 0; j < nb; ++j) {
    const LateralSupport& s = lat.supports[p.held[j]];
    p.middle[j] = lat.wires[s.wire].w_dof + s.node;
    middle_of[p.middle[j]] = j;
    rhs[p.middle[j]] = p.target[j];
  }
  for (const LateralSupport& s : lat.supports) {
    const int i = lat.wires[s.wire].w_dof + s.node;
    if (s.rigid && middle_of[i] < 0) {  // (a bridle's middle is held where its b says)
      rigid[i] = true;
      rhs[i] = s.stagger;
    }
  }
  std::vector<Eigen::Triplet<double>> entries;
  add_stiffness(m, lat, [&](int i, int j, double v) {
    if (i < n && (rigid[i] || middle_of[i] >= 0)) return;
    if (j < n && rigid[j]) rhs[i] -= v * rhs[j];
    else entries.emplace_back(i, j, v);
  });
  for (int i = 0; i < n; ++i) {
    if (rigid[i]) entries.emplace_back(i, i, 1.0);
    if (middle_of[i] >= 0) entries.emplace_back(i, at[middle_of[i]], 1.0);
  }
  Eigen::SparseMatrix<double> K(N, N);
  K.setFromTriplets(entries.begin(), entries.end());
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu(K);
  Eigen::VectorXd y;
  if (lu.info() == Eigen::Success) y = lu.solve(rhs);
  if (lu.info() != Eigen::Success || !y.allFinite())
    throw SceneError("bridle: no registration of the bridles' middles puts the contact wire at its stagger (the wire "
                     "is not held across the track through their clamps); report this with the scene");
  p.registration.resize(nb);
  p.ends.resize(2 * nb);
  for (int j = 0; j < nb; ++j) {
    const Wire& w = lat.wires[lat.supports[p.held[j]].wire];
    p.registration[j] = y[p.middle[j]];
    p.ends[2 * j] = y[w.w_dof];
    p.ends[2 * j + 1] = y[w.w_dof + w.nodes() - 1];
  }
  return p;
}

// The tension of `section`'s bridles that brings their steepest arm to kSteepestBridleArm, up and
// across the track together: the section's bridles hung and registered again at t2, each arm's
// two parts taken as a / T + b through t1 and t2 (a string's share falls as 1 / T, the bridle's
// bending's does not), and the tension at which the steepest meets the limit. None where the fit
// says no tension would do, or the second design fails.
std::optional<double> bridle_tension_needed(const Model& m, const LateralModel& lat, const BridlePlan& p, int section,
                                            double t1, double t2) {
  Model again = m;
  again.scene.sections[section].bridle->tension = t2;
  LateralModel lat2;
  BridlePlan p2;
  try {
    for (Wire& w : again.wires)
      if (w.is_bridle && w.section == section) {
        w.spec.tension = t2;
        assemble_band(w, {});
        std::vector<double> reaction;
        hang_bridle(again.scene, again, w, reaction);
      }
    add_wires_and_supports(again, &lat2);
    add_pendulums(again, &lat2);
    add_clamps(again, &lat2);
    p2 = plan_bridles(again, lat2);
  } catch (const SceneError&) {
    return std::nullopt;
  }
  if (p2.held.size() != p.held.size()) return std::nullopt;
  const double k = kSteepestBridleArm, s1 = 1.0 / t1, s2 = 1.0 / t2;
  double needed = t1;
  for (std::size_t j = 0; j < p.held.size(); ++j) {
    if (m.wires[lat.supports[p.held[j]].wire].section != section) continue;
    for (int e : {0, 1}) {
      const double c1 = p.across(m, lat, j, e), r1 = p.up(m, lat, j, e);
      if (!(std::hypot(c1, r1) > k)) continue;
      const double c2 = p2.across(again, lat2, j, e), r2 = p2.up(again, lat2, j, e);
      const double ac = (c1 - c2) / (s1 - s2), bc = c1 - ac * s1, ar = (r1 - r2) / (s1 - s2), br = r1 - ar * s1;
      // (ac s + bc)^2 + (ar s + br)^2 = k^2 in s = 1 / T: one positive root where the share
      // that does not fall with T is below the limit (C < 0).
      const double A = ac * ac + ar * ar, B = 2.0 * (ac * bc + ar * br), C = bc * bc + br * br - k * k;
      if (!(C < 0.0) || !(A > 0.0)) return std::nullopt;
      const double s = (-B + std::sqrt(B * B - 4.0 * A * C)) / (2.0 * A);
      if (!(s > 0.0)) return std::nullopt;
      needed = std::max(needed, 1.0 / s);
    }
  }
  return needed;
}

void register_bridles(const Model& m, LateralModel* lat) {
  const BridlePlan p = plan_bridles(m, *lat);
  const int nb = static_cast<int>(p.held.size());
  if (nb == 0) return;
  // The arms in the model's small angles, up and across the track together (their V alone is
  // checked in the design statics). Their slope in plan is what the wire's turn needs.
  double worst = 0.0, worst_plan = 0.0;
  int at_worst = -1;
  for (int j = 0; j < nb; ++j)
    for (int e : {0, 1}) {
      const double plan = p.across(m, *lat, j, e), slope = std::hypot(plan, p.up(m, *lat, j, e));
      if (!(slope <= worst) && !std::isnan(worst)) {  // (a NaN slope is the worst)
        worst = slope;
        worst_plan = plan;
        at_worst = j;
      }
    }
  if (!(worst <= kSteepestBridleArm)) {
    const Wire& w = m.wires[lat->supports[p.held[at_worst]].wire];
    const double t1 = m.scene.sections[w.section].bridle->tension;
    refuse_slack_bridle(m.scene, w, worst,
                        fmt(worst_plan) + " across the track, its middle " +
                            fmt(std::fabs(p.registration[at_worst] - p.target[at_worst])) + " m beyond the stagger",
                        ", shorten " + m.scene.section_field(w.section, "bridle.length") +
                            " (the wire turns between two bridles' clamps), or lessen the stagger or the curve there",
                        bridle_tension_needed(m, *lat, p, w.section, t1, t1 * worst / kSteepestBridleArm));
  }
  std::vector<int> spring_on(lat->n, -1);  // a lateral DOF's support spring (one at most: add_wires_and_supports)
  for (std::size_t k = 0; k < lat->springs.size(); ++k) spring_on[lat->springs[k].dof] = static_cast<int>(k);
  for (int j = 0; j < nb; ++j) {
    if (spring_on[p.middle[j]] >= 0) {
      LateralSpring& sp = lat->springs[spring_on[p.middle[j]]];
      lat->load[p.middle[j]] += sp.stiffness * (p.registration[j] - sp.anchor);
      sp.anchor = p.registration[j];
    }
    lat->supports[p.held[j]].stagger = p.registration[j];
  }
}

}  // namespace

void solve_lateral_statics(const Model& m, const LateralModel& lat, bool with_wind, Eigen::VectorXd* y_out,
                           std::vector<double>* force_on_support, const std::vector<double>* registration_travel) {
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
  if (registration_travel)
    for (std::size_t j = 0; j < lat.registrations.size(); ++j) {
      const LateralRegistration& r = lat.registrations[j];
      const double travel = (*registration_travel)[j];
      if (r.spring >= 0) F[r.dof] += lat.springs[r.spring].stiffness * travel;  // its anchor moved
      else fixed_value[r.dof] += travel;
    }
  const LateralSystem system(m, lat, fixed, force_on_support != nullptr);
  const Eigen::VectorXd x = system.solve(F, fixed_value).col(0);
  *y_out = x.head(n);
  if (force_on_support) support_forces(lat, F, system.full(), x, force_on_support);
}

std::vector<RegistrationLateral> registration_lateral(const Model& m, const std::vector<int>& dofs) {
  LateralModel lat;
  add_wires_and_supports(m, &lat);
  add_pendulums(m, &lat);
  add_clamps(m, &lat);
  const int n = lat.n;
  auto lateral_dof = [&](int vertical) { return lateral_dof_of(m, lat, vertical); };
  // Every support held (rows y_i = 0), then each asked node let go in turn: its stiffness is the
  // Schur complement K_ii - K_ir K_rr^-1 K_ri over the rest r of the plane. K_ri is nonzero on
  // the node's few neighbours, so only those entries of K_rr^-1 are needed: the selected inverse
  // gives them all in one sweep. (A solve per node would cost the whole plane's factor each, the
  // square of the spans: stitch wires chain the messenger's spans along the whole line, so no
  // arm's solve stays local.)
  std::vector<bool> fixed(n, false);
  std::vector<int> support_at(n, -1);  // a lateral DOF's support in lat.supports
  for (std::size_t k = 0; k < lat.supports.size(); ++k) {
    const int i = lat.wires[lat.supports[k].wire].w_dof + lat.supports[k].node;
    fixed[i] = true;
    support_at[i] = static_cast<int>(k);
  }
  // (Without the support's own lateral spring: that is the arm itself, stiff along its length.)
  std::vector<double> own(n, 0.0);
  for (const LateralSpring& sp : lat.springs) own[sp.dof] += sp.stiffness;
  std::vector<Eigen::Triplet<double>> entries;
  add_stiffness(m, lat, [&](int i, int j, double v) { entries.emplace_back(i, j, v); });
  Eigen::SparseMatrix<double> whole(2 * n, 2 * n);
  whole.setFromTriplets(entries.begin(), entries.end());
  std::vector<std::vector<std::pair<int, double>>> coupling(dofs.size());  // K_ri: (r, value)
  std::vector<std::pair<int, int>> pairs;
  for (std::size_t q = 0; q < dofs.size(); ++q) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(whole, lateral_dof(dofs[q])); it; ++it)
      if (!(it.row() < n && fixed[it.row()]) && it.value() != 0.0) coupling[q].emplace_back(it.row(), it.value());
    for (const auto& [a, va] : coupling[q])
      for (const auto& [b, vb] : coupling[q])
        if (a > b) pairs.emplace_back(a, b);
  }
  const LateralSystem held(std::move(whole), fixed, pairs);
  const SelectedInverse z = held.inverse();
  std::vector<RegistrationLateral> out(dofs.size());
  for (std::size_t q = 0; q < dofs.size(); ++q) {
    const int i = lateral_dof(dofs[q]);
    double through_rest = 0.0;  // K_ir K_rr^-1 K_ri
    for (const auto& [a, va] : coupling[q])
      for (const auto& [b, vb] : coupling[q]) through_rest += va * z(a, b) * vb;
    out[q].stiffness = held.full().coeff(i, i) - own[i] - through_rest;
  }
  if (!m.scene.lateral()) return out;
  // The calm statics in plan: each support's share of the wire's pull (the pull-off).
  Eigen::VectorXd y;
  std::vector<double> force;
  solve_lateral_statics(m, lat, false, &y, &force);
  for (std::size_t q = 0; q < dofs.size(); ++q) {
    const int k = support_at[lateral_dof(dofs[q])];
    if (k < 0) continue;
    out[q].pull_off = std::abs(force[k]);
    out[q].side = force[k] > 0.0 ? 1.0 : (force[k] < 0.0 ? -1.0 : 0.0);
  }
  return out;
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
  for (const SectionSpec& sec : sc.sections) {
    if (sec.stitch_wire) slowest = std::min(slowest, sigma(w.stitch_wire, sec.stitch_wire->linear_mass));
    if (sec.auxiliary_messenger)
      slowest = std::min(slowest, sigma(w.auxiliary_messenger, sec.auxiliary_messenger->linear_mass));
  }
  return slowest > kGustLeadDecays / kAutoGustLeadMax ? kGustLeadDecays / slowest : kAutoGustLeadMax;
}

int default_lead_every(const Model& m, const LateralModel& lat) {
  const std::optional<LeadStep>& step = m.scene.numerics.gust_lead_step;
  if (!lat.windowed || !(lat.gust_lead > 0.0) || lat.field.empty() || packs_of(m).empty()) return 0;
  if (step ? *step == LeadStep::kExplicit : !lat.clamps.empty()) return 0;
  return std::max(1, static_cast<int>(std::floor(kWindRefreshShare * lat.field.dt / m.dt + 1e-9)));
}

void set_lead_step(const Model& m, LateralModel& lat, int every) {
  lat.lead_every = every;
  if (every <= 0) return;
  lat.lead_dt = every * m.dt;
  lat.lead_beta = 0.5 * lat.lead_dt + m.beta;
  lat.lead_shift = (2.0 / lat.lead_dt + m.alpha) / lat.lead_beta;
  lat.lead_v_ratio = (2.0 / lat.lead_dt) / lat.lead_shift;
  // The springs and each pendulum's own end on the diagonal (the pendulums at their static
  // tension, as outside the vertical window), divided by shift: D + their stiffness.
  lat.lead_mass = lat.mass;
  for (const LateralSpring& sp : lat.springs) lat.lead_mass[sp.dof] += sp.stiffness / lat.lead_shift;
  for (const LateralPendulum& p : lat.pendulums) {
    const double k = std::max(0.0, m.droppers[p.dropper].static_tension) * p.inv_length;
    lat.lead_mass[p.contact] += k / lat.lead_shift;
    lat.lead_mass[p.messenger] += k / lat.lead_shift;
  }
}

std::shared_ptr<const LateralModel> design_lateral(const Model& m) {
  auto lat = std::make_shared<LateralModel>();
  add_wires_and_supports(m, lat.get());
  add_pendulums(m, lat.get());
  add_clamps(m, lat.get());
  register_bridles(m, lat.get());
  add_registrations(m, lat.get());
  if (m.scene.wind) add_wind(m, *m.scene.wind, lat.get());
  set_static_states(m, lat.get());
  return lat;
}

void check_lateral_design(const Model& m) { design_lateral(m); }

std::shared_ptr<const LateralModel> build_lateral(const Model& m) { return build_lateral(m, *design_lateral(m)); }

std::shared_ptr<const LateralModel> build_lateral(const Model& m, const LateralModel& design) {
  const Scene& sc = m.scene;
  auto lat = std::make_shared<LateralModel>(design);
  lat->windowed = sc.numerics.windowed() && (m.endless || lat->field.empty() || sc.numerics.gust_lead.has_value());
  lat->gust_lead = lat->windowed ? gust_lead_time(sc) : 0.0;
  const PantographHeadSpec& head = sc.pantograph_head;
  lat->half_working_width = 0.5 * head.working_width;
  lat->half_horn_width = 0.5 * head.horn_width;
  set_substeps(m, lat.get());
  build_lateral_packs(m, *lat);
  if (sc.numerics.damping == DampingStep::kCentred) factor_lateral_centred(m, *lat);
  prepare_window(lat.get());
  set_lead_step(m, *lat, default_lead_every(m, *lat));
  return lat;
}

double lean_coupled_omega_max(const Model& m, const LateralModel& lat) {
  const int nv = m.n_dof, n = nv + lat.n;
  Eigen::VectorXd s(n);
  s.head(nv) = m.inv_mass.cwiseSqrt();
  s.tail(lat.n) = lat.inv_mass.cwiseSqrt();
  int max_nodes = 1;
  for (const Wire& w : m.wires) max_nodes = std::max(max_nodes, w.nodes());
  std::vector<double> scratch(max_nodes), theta(lat.n);
  return 1.002 * power_iteration_omega(n, s.data(), 3000, [&](const double* x, double* y) {
    apply_stiffness(m, m.train_start, x, y, scratch.data(), true);  // y_v = K_v x_v
    double* yl = y + nv;
    const double* xl = x + nv;
    std::fill(yl, yl + lat.n, 0.0);
    elastic_force(m, lat, nullptr, xl, yl, theta.data());
    for (int i = 0; i < lat.n; ++i) yl[i] = -yl[i];
    for (const LateralPendulum& p : lat.pendulums) {
      const Dropper& d = m.droppers[p.dropper];
      const double slope = (lat.initial[p.messenger] - lat.initial[p.contact]) * p.inv_length;  // (lean0_sq's dy0)
      const double ks = d.stiffness * slope;
      const double dz = x[d.messenger_dof] - x[d.contact_dof], dy = xl[p.messenger] - xl[p.contact];
      y[d.messenger_dof] += ks * dy;
      y[d.contact_dof] -= ks * dy;
      yl[p.messenger] += ks * dz + ks * slope * dy;
      yl[p.contact] -= ks * dz + ks * slope * dy;
    }
  });
}


}  // namespace catenary_sim
