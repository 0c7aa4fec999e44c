// The lateral plane's step (lateral_step.hpp): explicit central differences of the lateral
// plane's own dt (substeps of the vertical one), fused as the vertical step's where the model has
// planes (wire_lanes.hpp), with the wind's drag, the steady arms as springs and the droppers as
// pendulums; then the contact points across the strips and dewirement.
#include "catenary_sim/core/engine/lateral_step.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "catenary_sim/core/engine/state.hpp"
#include "engine/centred_damping.hpp"
#include "model/centred_factors.hpp"
#include "engine/forces.hpp"
#include "engine/lateral_lead.hpp"
#include "engine/lateral_window.hpp"
#include "engine/lateral_wind.hpp"
#include "engine/lateral_workspace.hpp"
#include "engine/step_workspace.hpp"
#include "engine/window.hpp"
#include "engine/wire_lanes.hpp"
#include "util/deep_copied_impl.hpp"

namespace catenary_sim {

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

template class DeepCopied<LateralWorkspace>;  // LateralState::work

namespace {

// The wire's band force (f = -K y) at a held registration's node as a row over the nodes within
// kRegistrationReach of it (fewer at the wire's ends): the band over that range, rotations
// condensed there (its ends free, as a window's cut), applied to each node's unit displacement.
// Into the workspace's registration_first, _count and _row (kRegistrationRow values each).
void set_registration_row(const Model& m, LateralState& ls, int j) {
  const LateralModel& lat = *m.lateral;
  const LateralRegistration& r = lat.registrations[j];
  LateralWorkspace& lw = *ls.work;
  const Wire& w = lat.wires[r.wire];
  int lo = 0, hi = 0;
  registration_reach(r, w.nodes(), &lo, &hi);
  WireWindow range;
  range.tt_lower.assign(w.nodes(), 0.0);
  range.tt_inv_pivot.assign(w.nodes(), 0.0);
  set_wire_window(w, w.x[lo], w.x[hi], range);
  Eigen::VectorXd unit = Eigen::VectorXd::Zero(lat.n), f(lat.n);
  std::vector<double> theta(w.nodes());
  lw.registration_first[j] = w.w_dof + lo;
  lw.registration_count[j] = hi - lo + 1;
  for (int i = lo; i <= hi; ++i) {
    unit[w.w_dof + i] = 1.0;
    f.setZero();
    wire_elastic_force_window(w, range, unit.data(), f.data(), theta.data());
    lw.registration_row[j * kRegistrationRow + (i - lo)] = f[r.dof];
    unit[w.w_dof + i] = 0.0;
  }
}

// N, the lateral force on registration `j` (LateralModel::registrations) from everything but its
// arm, at the lateral state now: held, the wire's band (its row, set_registration_row; elastic,
// as the static pull-off is), the load at the node (a curve's T kappa h), the wind's drag on it
// and its droppers' pendulums; on a spring, the spring's pull k (y - anchor - travel) with
// `travel` the anchor's. `u`: the vertical plane's displacements (null: 0, the design state).
double registration_pull(const Model& m, const LateralState& ls, const double* u, int j, double travel) {
  const LateralModel& lat = *m.lateral;
  const LateralRegistration& r = lat.registrations[j];
  const double* y = ls.y.data();
  if (r.spring >= 0) {
    const LateralSpring& sp = lat.springs[r.spring];
    return sp.stiffness * (y[r.dof] - sp.anchor - travel);
  }
  const LateralWorkspace& lw = *ls.work;
  const double* row = lw.registration_row.data() + j * kRegistrationRow;
  const double* near = y + lw.registration_first[j];
  double band = 0.0;
  for (int k = 0; k < lw.registration_count[j]; ++k) band += row[k] * near[k];
  double pull = lat.load[r.dof] + band;
  if (lat.windy) {
    const double vn = ls.wind_speed[r.dof] - ls.v[r.dof];
    pull += lat.wind_coefficient[r.dof] * vn * std::fabs(vn);
  }
  for (int q : r.pendulums) {  // as add_springs_and_pendulums, at y
    const LateralPendulum& p = lat.pendulums[q];
    const Dropper& d = m.droppers[p.dropper];
    const double stretch = (u ? u[d.messenger_dof] - u[d.contact_dof] : 0.0) + lean_stretch(p, y);
    const double tension = d.static_tension + d.stiffness * stretch;
    pull += std::max(0.0, tension) * p.inv_length * (y[p.messenger] - y[p.contact]);
  }
  return pull;
}

// tan(theta) of the arm with its end raised by u: d(travel)/du, side apart.
double arm_tan(const LateralRegistration& r, double u) {
  const double sin_theta = std::clamp(r.sin0 - u / r.length, -1.0, 1.0);
  return sin_theta / std::sqrt(1.0 - sin_theta * sin_theta);
}

}  // namespace

LateralState make_lateral_state(const Model& m) {
  const LateralModel& lat = *m.lateral;
  LateralState s;
  LateralWorkspace& work = *s.work;
  s.y = lat.initial;
  s.v = Eigen::VectorXd::Zero(lat.n);
  work.f = Eigen::VectorXd::Zero(lat.n);
  work.z = Eigen::VectorXd::Zero(lat.n);
  work.y_next = s.y;
  work.v_next = Eigen::VectorXd::Zero(lat.n);
  work.accel = Eigen::VectorXd::Zero(lat.n);
  work.sweep.assign(2 * kCentredRecord * sweep_size(m), 0.0);  // (both planes' records when joint)
  int longest = 0;
  for (const Wire& w : lat.wires) longest = std::max(longest, w.nodes());
  work.theta.assign(longest, 0.0);
  s.wind_points.assign(std::max(0, lat.field.held), 0.0);
  if (m.endless) s.wind_field.reset(lat.field);  // (nothing for a steady wind)
  if (lat.windy) s.wind_speed = lat.wind_speed * lat.wind_normal;  // the mean wind until the field's first refresh
  s.contact_lateral.assign(m.collectors.size() * m.contact_wires.size(), std::nan(""));
  s.collector_lateral.assign(m.collectors.size(), std::nan(""));
  s.collector_wire.assign(m.collectors.size(), -1);
  s.pantograph_lateral.assign(m.pantographs.size(), 0.0);
  s.off_strip.assign(m.collectors.size(), 0);
  s.events.reserve(kMaxDewirementEvents);
  s.dropper_stretch.assign(m.droppers.size(), 0.0);
  s.registration_travel.assign(lat.registrations.size(), 0.0);  // (u = 0: the arms as built)
  s.registration_force.assign(lat.registrations.size(), 0.0);
  work.lean_weight.assign(m.droppers.size(), 1.0);
  for (const LateralPendulum& p : lat.pendulums) s.dropper_stretch[p.dropper] = lean_stretch(p, s.y.data());  // 0: y is initial
  s.window.resize(lat.wires.size());
  for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) {
    s.window[wi].tt_lower.assign(lat.wires[wi].nodes(), 0.0);
    s.window[wi].tt_inv_pivot.assign(lat.wires[wi].nodes(), 0.0);
  }
  if (!lat.registrations.empty()) {
    const int nr = static_cast<int>(lat.registrations.size());
    work.registration_first.assign(nr, 0);
    work.registration_count.assign(nr, 0);
    work.registration_row.assign(static_cast<std::size_t>(nr) * kRegistrationRow, 0.0);
    work.registration_swept.assign(nr, 0.0);
    for (int j = 0; j < nr; ++j)
      if (lat.registrations[j].spring < 0) set_registration_row(m, s, j);
    // (At rest in the static state under the mean wind, with every arm as built.)
    for (int j = 0; j < nr; ++j) work.registration_pull0.push_back(registration_pull(m, s, nullptr, j, 0.0));
  }
  if (lat.windowed && !lat.planes.empty() && lat.centred_twin.empty()) work.sweep_factors.assign(2 * sweep_size(m), 0.0);
  work.window_springs.assign(lat.springs.size(), 0);
  work.window_droppers.assign(lat.pendulums.size(), 0);
  work.window_clamps.assign(lat.clamps.size(), 0);
  work.cut_node.assign(2 * kCutLayer * m.wires.size(), 0);
  work.cut_force.assign(work.cut_node.size(), 0.0);
  if (lat.lead_every > 0) {
    s.lead_y = s.lead_y_before = lat.initial;
    s.lead_v = s.lead_v_before = Eigen::VectorXd::Zero(lat.n);
    s.lead_window.resize(lat.wires.size());
    for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) {
      s.lead_window[wi].tt_lower.assign(lat.wires[wi].nodes(), 0.0);
      s.lead_window[wi].tt_inv_pivot.assign(lat.wires[wi].nodes(), 0.0);
    }
    work.lead_droppers.assign(lat.pendulums.size(), 0);
    work.lead_cut_node.assign(2 * kCutLayer * m.wires.size(), 0);
    work.lead_cut_force.assign(work.lead_cut_node.size(), 0.0);
    work.lead_held.assign(lat.n, 0);
    work.lead_extra_node.assign(lat.n, 0);
    work.lead_extra_diag.assign(lat.n, 0.0);
    work.lead_dashpot_node.assign(2 * lat.wires.size(), 0);
    work.lead_dashpot.assign(2 * lat.wires.size(), 0.0);
    work.lead_plane_mass = lat.lead_mass;
    work.lead_f = work.lead_y_next = work.lead_v_next = work.lead_accel = work.lead_wind = Eigen::VectorXd::Zero(lat.n);
    work.lead_points.assign(std::max(0, lat.field.held), 0.0);
    if (m.endless) {
      work.lead_wind_point.assign(lat.n, 0);
      work.lead_wind_weight.assign(lat.n, 0.0);
    }
    std::size_t twin = 0, single = 0;
    for (const WireLanes& p : packs_of(m)) {  // (a range has at most its wires' nodes)
      work.lead_twin_at.push_back(twin);
      work.lead_single_at.push_back(single);
      twin += static_cast<std::size_t>(centred_meeting_node(p.nodes)) * kCdValues * 2 * p.lanes;
      single += 2 * kCdValues * static_cast<std::size_t>(p.lanes);
    }
    work.lead_twin.assign(twin, 0.0);
    work.lead_single.assign(single, 0.0);
    work.lead_scratch.assign(static_cast<std::size_t>(longest) * kCdValues, 0.0);
    work.lead_record.assign(kCentredRecord * sweep_size(m), 0.0);
  }
  work.window_points.assign(work.cut_node.size() + lat.springs.size() + 2 * lat.pendulums.size() + 2 * lat.clamps.size() +
                                kRegistrationRow * lat.registrations.size(),
                            0);
  if (lat.windowed && !lat.centred_twin.empty()) {
    // A window's range has at most its wires' nodes: the whole wires' layout sizes it.
    std::size_t twin = 0, single = 0;
    for (std::size_t pk = 0; pk < lat.centred_twin.size(); ++pk) {
      work.centred_twin_at.push_back(twin);
      work.centred_single_at.push_back(single);
      twin += lat.centred_twin[pk].size();
      single += lat.centred_single[pk].size();
    }
    work.centred_twin.assign(twin, 0.0);
    work.centred_single.assign(single, 0.0);
    work.centred_scratch.assign(static_cast<std::size_t>(longest) * kCdValues, 0.0);
  }
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
        const Wire& w = lat.wires[m.contact_wires[wk]];  // (the vertical plane's nodes: the same patch)
        const ContactPatch cp = contact_patch(m, *s.work, ci, wk, xc);
        double y = 0.0;
        for (int a = 0; a < cp.count; ++a) y += cp.weight[a] * ls.y[w.w_dof + cp.node[a]];
        ls.contact_lateral[ci * nw + wk] = cp.count ? y - sway : std::nan("");
        const double fc = s.contact_force[ci * nw + wk];
        if (cp.count && fc > best_force) {
          best_force = fc;
          running = static_cast<int>(wk);
        }
      }
      if (running < 0) lowest_design_height(m, xc, &running);  // not touching: the wire it meets first
      const double yc = running >= 0 ? ls.contact_lateral[ci * nw + running] : std::nan("");
      ls.collector_lateral[ci] = yc;
      ls.collector_wire[ci] = running;
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

// The springs (steady arms, messenger supports), the droppers' pendulums and the stitch wires'
// clamps on f, at z = y + beta v (`z_at`), over the window's lists or the whole line: the
// pendulums at the droppers' tension now with their lean's share (two-way coupling, lateral.hpp),
// 0 when slack, and each lean summed into dropper_stretch for the next vertical step; the clamps
// bilateral, never slack. The fused and the generic step share it, so they do the same operations.
template <class ZAt>
void add_springs_and_pendulums(const Model& m, State& s, bool windowed, const double* y, ZAt z_at, double* f) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  LateralWorkspace& lw = *ls.work;
  const int n_springs = windowed ? lw.window_spring_count : static_cast<int>(lat.springs.size());
  for (int j = 0; j < n_springs; ++j) {
    const LateralSpring& sp = lat.springs[windowed ? lw.window_springs[j] : j];
    f[sp.dof] -= sp.stiffness * z_at(sp.dof);
  }
  // A hinged arm's registration on its spring: the anchor moved by the arm's end's travel, the
  // load's k stagger and k travel (outside the window nothing is stepped). Held, moved by d since
  // the band sweep took it (place_at_arms): -K d on its row's nodes, the row's values being the
  // band's -K (symmetric), as if the sweep had seen it moved.
  const double* travel = ls.registration_travel.data();
  const double* swept = lw.registration_swept.data();
  for (std::size_t j = 0; j < lat.registrations.size(); ++j) {
    const LateralRegistration& r = lat.registrations[j];
    const WireWindow& ww = ls.window[r.wire];
    if (windowed && !(r.node >= ww.lo && r.node <= ww.hi)) continue;
    if (r.spring >= 0) {
      f[r.dof] += lat.springs[r.spring].stiffness * travel[j];
      continue;
    }
    const double d = y[r.dof] - swept[j];
    if (d == 0.0) continue;
    const int first = lw.registration_first[j], count = lw.registration_count[j];
    const int w0 = lat.wires[r.wire].w_dof;
    const int k0 = windowed ? std::max(0, w0 + ww.lo - first) : 0;
    const int k1 = windowed ? std::min(count, w0 + ww.hi + 1 - first) : count;
    const double* row = lw.registration_row.data() + j * kRegistrationRow;
    for (int k = k0; k < k1; ++k)
      if (first + k != r.dof) f[first + k] += row[k] * d;
  }
  const double* u = s.u.data();
  double* stretch = ls.dropper_stretch.data();
  const double* w = lw.lean_weight.data();
  const int n_pendulums = windowed ? lw.window_dropper_count : static_cast<int>(lat.pendulums.size());
  for (int j = 0; j < n_pendulums; ++j) {
    const LateralPendulum& p = lat.pendulums[windowed ? lw.window_droppers[j] : j];
    const Dropper& d = m.droppers[p.dropper];
    const double lean = lean_stretch(p, y);
    stretch[p.dropper] += lean;
    const double tension = d.static_tension + d.stiffness * ((u[d.messenger_dof] - u[d.contact_dof]) + lean * w[p.dropper]);
    const double k = std::max(0.0, tension) * p.inv_length;
    const double df = k * (z_at(p.messenger) - z_at(p.contact));
    f[p.contact] += df;
    f[p.messenger] -= df;
  }
  const int n_clamps = windowed ? lw.window_clamp_count : static_cast<int>(lat.clamps.size());
  for (int j = 0; j < n_clamps; ++j) {
    const LateralClamp& c = lat.clamps[windowed ? lw.window_clamps[j] : j];
    const double df = c.stiffness * (z_at(c.upper) - z_at(c.lower));
    f[c.lower] += df;
    f[c.upper] -= df;
  }
}

// The substep's new values (y_next, v_next) into the state once all are good: swapped in, or in
// the window copied back (outside it the new buffers hold nothing current).
void commit_substep(const Model& m, State& s, bool windowed) {
  LateralState& ls = s.lateral;
  LateralWorkspace& lw = *ls.work;
  if (!windowed) {
    ls.y.swap(lw.y_next);  // O(1)
    ls.v.swap(lw.v_next);
    return;
  }
  double* y = ls.y.data();
  double* v = ls.v.data();
  const double* yn = lw.y_next.data();
  const double* vn = lw.v_next.data();
  over_stepped(m, s, true, [&](int i0, int i1) {
    for (int i = i0; i < i1; ++i) {
      y[i] = yn[i];
      v[i] = vn[i];
    }
  });
}

// Each held registration's y swapped with where the band sweep takes it (registration_swept).
void swap_swept_registrations(const Model& m, State& s) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  double* swept = ls.work->registration_swept.data();
  for (std::size_t j = 0; j < lat.registrations.size(); ++j)
    if (lat.registrations[j].spring < 0) std::swap(ls.y[lat.registrations[j].dof], swept[j]);
}

// The band sweeps from here on take each held registration where it is.
void sweep_registrations_where_they_are(const Model& m, State& s) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  double* swept = ls.work->registration_swept.data();
  for (std::size_t j = 0; j < lat.registrations.size(); ++j)
    if (lat.registrations[j].spring < 0) swept[j] = ls.y[lat.registrations[j].dof];
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
  LateralWorkspace& lw = *ls.work;
  const double h = lat.dt, beta = m.beta, limit = m.scene.numerics.divergence_limit;
  const double* y = ls.y.data();
  const double* v = ls.v.data();
  double* yn = lw.y_next.data();
  double* vn = lw.v_next.data();
  double* acc = lw.accel.data();
  // The band sweeps: taken along by this step's vertical sweeps (step_both_planes), else here.
  const bool joined = lw.joined;  // (its records then in the joint layout: LateralModel::joint_force_at)
  bool outside = joined && lw.joined_outside;
  if (!joined) {
    // (Held registrations where the joint sweep would have seen them: the same bits either way.)
    swap_swept_registrations(m, s);
    for (std::size_t pk = 0; pk < packs_of(m).size(); ++pk) {
      PackSweep a;
      if (setup_lateral_sweep(m, s, pk, windowed, a)) outside |= sweep_pack(a);
    }
    swap_swept_registrations(m, s);
  }
  lw.joined = false;
  // Point forces on the band forces the sweep left in its records, as the generic step adds them.
  double* f = lw.f.data();
  const double* rec = joined ? lw.sweep.data() : s.work->sweep.data();
  const int* at = joined ? lat.joint_force_at.data() : lat.sweep_force_at.data();
  const int* points = windowed ? lw.window_points.data() : lat.point_nodes.data();
  const int np = windowed ? lw.window_point_count : static_cast<int>(lat.point_nodes.size());
  for (int q = 0; q < np; ++q) f[points[q]] = rec[at[points[q]]];
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
  commit_substep(m, s, windowed);
  return false;
}

// The forces of a lateral substep with centred damping: the load, the wind's drag on the wire's
// velocity v_{n-1/2} (aerodynamic damping, explicit as in the half-step), the window's forces,
// springs and pendulums on z = y + beta v, 0 on a held node (its row is zeta = y).
void centred_forces(const Model& m, State& s, bool windowed) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  const double beta = m.beta;
  const double* load = lat.load.data();
  const double* y = ls.y.data();
  const double* v = ls.v.data();
  double* f = ls.work->f.data();
  over_stepped(m, s, windowed, [&](int i0, int i1) {
    if (lat.windy) {
      const double* cw = lat.wind_coefficient.data();
      const double* W = ls.wind_speed.data();
      for (int i = i0; i < i1; ++i) {
        const double vn = W[i] - v[i];
        f[i] = load[i] + cw[i] * vn * std::fabs(vn);
      }
    } else {
      for (int i = i0; i < i1; ++i) f[i] = load[i];
    }
  });
  if (windowed) add_window_forces(m, s, v, f);
  add_springs_and_pendulums(m, s, windowed, y, [y, v, beta](int i) { return y[i] + beta * v[i]; }, f);
  for (int d : lat.centred_held) f[d] = 0.0;
}

// One lateral substep with centred damping (engine/centred_damping.hpp, in the lateral plane at its
// own dt): its forces (centred_forces), then per pack the wires' solve for zeta (their Rayleigh
// damping, alpha M + beta K, taken at the step's middle) and the update. Where the vertical step
// took the solve along (take_centred_solve_along), only the packs it left. The new values go to
// y_next, v_next and are swapped in (copied back in the window) when all are inside the divergence
// limit; else the state keeps the last good substep and this returns true.
bool centred_substep(const Model& m, State& s, bool windowed) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  LateralWorkspace& lw = *ls.work;
  const bool joined = lw.joined;
  lw.joined = false;
  if (!joined) centred_forces(m, s, windowed);
  const CentredArrays plane{ls.y.data(), ls.v.data(), lw.f.data(), lw.y_next.data(), lw.v_next.data(), lw.accel.data()};
  const std::vector<WireLanes>& packs = packs_of(m);
  bool out = joined && lw.joined_outside;
  for (std::size_t pk = 0; pk < packs.size(); ++pk) {
    if (joined && joins_centred(m, pk)) continue;
    const WireLanes& p = packs[pk];
    const WireWindow& ww = ls.window[p.wire[0]];
    const int lo = windowed ? ww.lo : 0, hi = windowed ? ww.hi : p.nodes - 1;
    if (hi < lo) continue;
    CentredSweep c;
    c.lanes = p.lanes;
    for (int k = 0; k < p.lanes; ++k) c.lane[k] = plane.at(lat.wires[p.wire[k]].w_dof + lo);
    c.nodes = hi - lo + 1;
    c.dt = lat.dt;
    c.v_ratio = lat.centred_v_ratio;
    c.beta = m.beta;
    c.limit = m.scene.numerics.divergence_limit;
    c.twin = windowed ? lw.centred_twin.data() + lw.centred_twin_at[pk] : lat.centred_twin[pk].data();
    c.single = windowed ? lw.centred_single.data() + lw.centred_single_at[pk] : lat.centred_single[pk].data();
    c.record = lw.sweep.data() + kCentredRecord * p.offset;
    out |= centred_sweep(c) != 0;
  }
  if (out) return true;
  commit_substep(m, s, windowed);
  return false;
}

// One lateral substep, the generic step (what the fused one computes, bit for bit: test_lateral):
// the force on z = y + beta v with the load, damping and the wind's drag on the wire's velocity
// (aerodynamic damping), the band, the window's forces, springs and pendulums, then the update
// into y_next, v_next, swapped in (copied back in the window) when all are good. True if a new
// displacement left the divergence limit: the state keeps the last good substep.
bool generic_substep(const Model& m, State& s, bool windowed) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  LateralWorkspace& lw = *ls.work;
  const double h = lat.dt, beta = m.beta, alpha = m.alpha;
  const double* load = lat.load.data();
  const double* mass = lat.mass.data();
  const double* inv_mass = lat.inv_mass.data();
  double* f = lw.f.data();
  double* z = lw.z.data();
  const double limit = m.scene.numerics.divergence_limit;
  const double* y = ls.y.data();
  const double* v = ls.v.data();
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
  // The band at each held registration where the fused step's sweep takes it (fused_substep).
  const double* swept = lw.registration_swept.data();
  for (std::size_t j = 0; j < lat.registrations.size(); ++j) {
    const LateralRegistration& r = lat.registrations[j];
    if (r.spring < 0) z[r.dof] = swept[j] + beta * v[r.dof];
  }
  if (windowed) {
    for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) wire_elastic_force_window(lat.wires[wi], ls.window[wi], z, f, lw.theta.data());
    add_window_forces(m, s, v, f);
  } else {
    for (const Wire& w : lat.wires) wire_elastic_force(w, z, f, lw.theta.data());
  }
  for (const LateralRegistration& r : lat.registrations)
    if (r.spring < 0) z[r.dof] = y[r.dof] + beta * v[r.dof];
  add_springs_and_pendulums(m, s, windowed, y, [z](int i) { return z[i]; }, f);
  double* yn = lw.y_next.data();
  double* vn = lw.v_next.data();
  int out = 0;  // an integer OR vectorises where a max over doubles (NaN rules) does not
  over_stepped(m, s, windowed, [&](int i0, int i1) {
    for (int i = i0; i < i1; ++i) {
      const double a = inv_mass[i] * f[i];  // eq. 20-21, in the fused sweep's order
      vn[i] = v[i] + h * a;
      yn[i] = y[i] + h * vn[i];
      out |= !(std::fabs(yn[i]) <= limit);  // also NaN
    }
  });
  if (out) return true;
  commit_substep(m, s, windowed);
  return false;
}

// A substep (or, `lead`, a step of the implicit gust lead) left the divergence limit: the first
// DOF beyond it among the rejected values (every step leaves them in its new buffer) reported.
StepStatus lateral_diverged(const Model& m, State& s, bool lead) {
  LateralState& ls = s.lateral;
  LateralWorkspace& lw = *ls.work;
  ls.diverged = true;
  const double* yn = lead ? lw.lead_y_next.data() : lw.y_next.data();
  const double limit = m.scene.numerics.divergence_limit;
  ls.diverged_node = -1;
  auto first_beyond = [&](int i0, int i1) {
    for (int i = i0; i < i1 && ls.diverged_node < 0; ++i)
      if (!(std::fabs(yn[i]) <= limit)) {
        ls.diverged_node = i;
        ls.diverged_position = yn[i];
      }
  };
  if (lead) {
    for (std::size_t wi = 0; wi < m.lateral->wires.size(); ++wi) {
      const WireWindow& ww = ls.lead_window[wi];
      if (ww.hi >= ww.lo) first_beyond(m.lateral->wires[wi].w_dof + ww.lo, m.lateral->wires[wi].w_dof + ww.hi + 1);
    }
  } else {
    over_stepped(m, s, m.lateral->windowed, first_beyond);
  }
  s.status = StepStatus::kDiverged;
  return s.status;
}

// The hinged arms' registrations (LateralModel::registrations), both ways. A lateral step reads
// the u the vertical step has just reached (the droppers' lean too: lateral.hpp): at its start
// each registration point is put where its arm's end is at that u (place_at_arms; held, the node
// at rest there through the step's substeps; on a spring, its anchor), and the wire's lateral
// force on it, averaged over the substeps as the lean's stretch is (add_registration_pulls),
// acts on the arm's end in the next vertical step, (F - F0) side tan(theta(u))
// (set_registration_forces). Every force of both planes is so taken at one configuration, which
// keeps the partitioned step symplectic (line_energy is conserved), and the arm's end is on its
// circle whenever a step ends. The first substep's band sweep takes a held registration where the
// last step put it (registration_swept: so the vertical step can take that sweep along before
// this step places it, step.cpp), and the point forces add its move's share on its row's nodes.
void place_at_arms(const Model& m, State& s) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  for (std::size_t j = 0; j < lat.registrations.size(); ++j) {
    const LateralRegistration& r = lat.registrations[j];
    ls.registration_travel[j] = registration_travel(r, s.u[r.vertical]);
    if (r.spring < 0) {
      ls.work->registration_swept[j] = ls.y[r.dof];  // (where this step's joint sweep took it)
      ls.y[r.dof] = lat.initial[r.dof] + ls.registration_travel[j];
      ls.v[r.dof] = 0.0;
    }
    ls.registration_force[j] = 0.0;  // (the sum of the step's pulls from here)
  }
}

void add_registration_pulls(const Model& m, State& s) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  for (std::size_t j = 0; j < lat.registrations.size(); ++j)
    ls.registration_force[j] += registration_pull(m, ls, s.u.data(), static_cast<int>(j), ls.registration_travel[j]);
}

void set_registration_forces(const Model& m, State& s, int pulls) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  const double* pull0 = ls.work->registration_pull0.data();
  for (std::size_t j = 0; j < lat.registrations.size(); ++j) {
    const LateralRegistration& r = lat.registrations[j];
    ls.registration_force[j] = (ls.registration_force[j] / pulls - pull0[j]) * r.side * arm_tan(r, s.u[r.vertical]);
  }
}

// registration_force from the wire's pull in the lateral state as it is (no substeps to average).
void set_registration_forces_now(const Model& m, State& s) {
  add_registration_pulls(m, s);
  set_registration_forces(m, s, 1);
}

}  // namespace

StepStatus lateral_step(const Model& m, State& s) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  LateralWorkspace& lw = *ls.work;
  const double h = lat.dt;
  const double t0 = s.time - m.dt;  // the vertical step has already moved the clock on
  // The droppers' lean over this step's substeps (all at this u), for the next vertical step.
  for (double& e : ls.dropper_stretch) e = 0.0;
  if (m.scene.numerics.windowed()) {
    // Outside the vertical plane's window the droppers' ends are held vertically (the window does
    // not move them), so a lean there would load the dropper with k delta against rigid wires,
    // where the free line gives way (delta / (1/k + f_c + f_m), some 1/300 of it): the lean acts on
    // the tension only inside the window, as in the vertical step.
    for (double& x : lw.lean_weight) x = 0.0;
    for (int j = 0; j < s.window_dropper_count; ++j) lw.lean_weight[s.window_droppers[j]] = 1.0;
  }
  const bool windowed = lat.windowed;
  // The implicit gust lead up to this step's start, so that the nodes the window reaches take its
  // state then; then placed ahead of the window as it stands.
  if (lat.lead_every > 0 && advance_lead(m, s, t0)) return lateral_diverged(m, s, true);
  if (windowed) sync_window(m, s);
  if (lat.lead_every > 0) sync_lead(m, s);
  const bool arms = !lat.registrations.empty();
  const bool centred = !lat.centred_twin.empty();
  // A plane that nothing loads but its constant load (no wind, no droppers, whose tension moves
  // with the vertical plane, no hinged arms: a rigid rail's), at rest in its static state, would
  // only gather round-off: left there. Moved from it (a pluck), it is stepped.
  const bool still = !lat.windy && lat.pendulums.empty() && lat.registrations.empty();
  const bool resting = still && ls.v.isZero(0.0) && ls.y == lat.initial;
  if (arms) {
    place_at_arms(m, s);
    // The centred step's solve takes the band at the registrations as placed (no joint sweep).
    if (centred) sweep_registrations_where_they_are(m, s);
  }
  for (int sub = 0; sub < (resting ? 0 : lat.substeps); ++sub) {
    refresh_wind_if_due(m, s, t0 + sub * h, windowed);
    if (arms) add_registration_pulls(m, s);
    const bool fused = !lat.planes.empty() && (!windowed || lw.window_fused);
    const bool failed = centred ? centred_substep(m, s, windowed)
                        : fused ? fused_substep(m, s, windowed)
                                : generic_substep(m, s, windowed);
    if (failed) return lateral_diverged(m, s, false);
    if (arms) sweep_registrations_where_they_are(m, s);
  }
  lw.joined = false;  // (a resting plane leaves unused a sweep the vertical step took along)
  const double per_substep = 1.0 / lat.substeps;
  for (double& e : ls.dropper_stretch) e *= per_substep;
  if (arms) set_registration_forces(m, s, lat.substeps);
  update_head_wind(m, s, &field_values(m, s), ls.wind_points.data());
  const bool left = contact_points(m, s, true);
  if (left && m.scene.pantograph_head.on_dewirement == DewirementAction::kStop) {
    ls.dewired_stop = true;
    s.status = StepStatus::kDewired;
  }
  return s.status;
}

bool take_centred_solve_along(const Model& m, State& s) {
  if (m.lateral->centred_joint_twin.empty()) return false;
  refresh_wind_before_joint_step(m, s);
  centred_forces(m, s, false);
  return true;
}

void shift_lateral_block(const Model& m, State& s) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  LateralWorkspace& lw = *ls.work;
  const bool windowed = lat.windowed;  // (an endless line always is)
  // A stitched line's stitch wires (hand_over_clamped_wires): the window's state handed over (the
  // stagger repeats with the move, so their static states are alike); the nodes it leaves, and the
  // last wires', to the static state under the mean wind at rest.
  auto to_rest = [&](int wire, const WireWindow& ww) {
    const int o = lat.wires[wire].w_dof;
    for (int i = std::max(0, ww.lo); i <= ww.hi; ++i) {
      ls.y[o + i] = lat.initial[o + i];
      ls.v[o + i] = 0.0;
    }
  };
  hand_over_clamped_wires(
      m, ls.window,
      [&](int to, int from, const WireWindow& fw) {
        to_rest(to, ls.window[to]);
        const int o = lat.wires[to].w_dof, src = lat.wires[from].w_dof;
        for (int i = std::max(0, fw.lo); i <= fw.hi; ++i) {
          ls.y[o + i] = ls.y[src + i];
          ls.v[o + i] = ls.v[src + i];
          if (lat.windy) ls.wind_speed[o + i] = ls.wind_speed[src + i];
        }
      },
      to_rest);
  for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) {
    const Wire& w = lat.wires[wi];
    if (w.is_clamped_wire) continue;
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
  lw.window_dirty = true;  // the lists and factors hold the old DOFs (the node ranges already match)
  if (lat.lead_every > 0) shift_lead(m, s);
  set_dropper_stretch(m, s);  // the droppers' lean moved with the block
  // The hinged arms' registrations (held ones were left with the held nodes) where their arms'
  // ends are at the moved u (shift_endless_block moved it first), and the wire's answer there.
  if (!lat.registrations.empty()) {
    place_at_arms(m, s);
    set_registration_forces_now(m, s);
  }
  if (lat.windy && !lat.field.empty()) {
    // The spans entering ahead take the wind of the last refresh at their stations (sync_window):
    // the field generated that far (the caller moves line_offset on by the shift after this), and
    // the held points' values at that refresh.
    extend_endless_field(m, s, s.line_offset + m.endless_shift_spans * m.endless_span);
    ls.wind_field.at_time(lat.field, ls.wind_time, ls.wind_points.data());
  }
}

double lateral_position(const Model& m, const State& s, int dof) {
  const LateralModel& lat = *m.lateral;
  const LateralState& ls = s.lateral;
  if (lat.lead_every > 0 && !ls.lead_window.empty() && !in_windows(lat.wires, ls.window, dof) &&
      in_windows(lat.wires, ls.lead_window, dof)) {
    double y = 0.0, v = 0.0;
    lead_state_at(m, s, dof, s.time, &y, &v);
    return y;
  }
  return ls.y[dof];
}

void place_registrations(const Model& m, State& s) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  place_at_arms(m, s);
  bool moved = false;
  for (double t : ls.registration_travel) moved |= t != 0.0;
  if (moved) {
    // The lateral statics with the registrations moved (the static state under the mean wind when
    // none is), at rest, so that the wire's answer on each arm starts as it goes on.
    Eigen::VectorXd y;
    solve_lateral_statics(m, lat, true, &y, nullptr, &ls.registration_travel);
    ls.y = y;
    ls.v.setZero();
    set_dropper_stretch(m, s);
  }
  set_registration_forces_now(m, s);
}

void set_dropper_stretch(const Model& m, State& s) {
  for (const LateralPendulum& p : m.lateral->pendulums)
    s.lateral.dropper_stretch[p.dropper] = lean_stretch(p, s.lateral.y.data());
}

}  // namespace catenary_sim
