#include "catenary_sim/core/model/statics.hpp"

#include "model/assembly.hpp"
#include "model/spd_solver.hpp"
#include "util/format.hpp"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace catenary_sim {

void solve_wire_statics(const Wire& wire, const std::vector<double>& node_load, const std::vector<int>& pn,
                        const std::vector<double>& ph, std::vector<double>& height, std::vector<double>& slope,
                        std::vector<double>& reactions, SpdSolver* solver) {
  const int n = wire.nodes();
  Triplets t;
  t.reserve(12 * static_cast<std::size_t>(n));  // add_wire_band's: 4 a node, 8 an element
  add_wire_band(t, wire, 0, n);
  Eigen::SparseMatrix<double> k(2 * n, 2 * n);
  k.setFromTriplets(t.begin(), t.end());
  // Prescribed heights: move the known columns to the right-hand side, identity rows.
  std::vector<double> fixed(2 * n, std::nan(""));
  for (std::size_t j = 0; j < pn.size(); ++j) fixed[pn[j]] = ph[j];
  Eigen::VectorXd r = Eigen::VectorXd::Zero(2 * n);
  for (int i = 0; i < n; ++i) r[i] = node_load[i];
  Eigen::VectorXd yp = Eigen::VectorXd::Zero(2 * n);
  for (int i = 0; i < 2 * n; ++i)
    if (!std::isnan(fixed[i])) yp[i] = fixed[i];
  r -= k * yp;
  Triplets tr;
  tr.reserve(t.size() + 2 * static_cast<std::size_t>(n));
  for (const auto& e : t) {
    const bool fr = !std::isnan(fixed[e.row()]), fc = !std::isnan(fixed[e.col()]);
    if (!fr && !fc) tr.push_back(e);
  }
  for (int i = 0; i < 2 * n; ++i)
    if (!std::isnan(fixed[i])) {
      tr.emplace_back(i, i, 1.0);
      r[i] = fixed[i];
    }
  Eigen::SparseMatrix<double> kr(2 * n, 2 * n);
  kr.setFromTriplets(tr.begin(), tr.end());
  SpdSolver own;
  const Eigen::VectorXd y = (solver ? *solver : own).solve(kr, r, "the " + wire.name + " statics");
  height.assign(y.data(), y.data() + n);
  slope.assign(y.data() + n, y.data() + 2 * n);
  const Eigen::VectorXd ky = k * y;
  reactions.resize(pn.size());
  for (std::size_t j = 0; j < pn.size(); ++j) reactions[j] = ky[pn[j]] - node_load[pn[j]];
}

namespace {

// The unknowns of eq. 23: the model's DOFs, then the rotations of the wires whose rotations the
// step condenses (statics solves for them directly). theta0[i]: wire i's first rotation.
struct StaticUnknowns {
  std::vector<int> theta0;
  int size = 0;
};

StaticUnknowns static_unknowns(const Model& m) {
  StaticUnknowns q;
  q.theta0.resize(m.wires.size());
  q.size = m.n_dof;
  for (std::size_t i = 0; i < m.wires.size(); ++i) {
    q.theta0[i] = m.wires[i].theta_dof >= 0 ? m.wires[i].theta_dof : q.size;
    if (m.wires[i].theta_dof < 0) q.size += m.wires[i].nodes();
  }
  return q;
}

// The active set of eq. 25: which droppers are taut (tension only) and which collector presses
// on which contact wire (compression only, per collector x contact wire). All on at the start.
struct ActiveSet {
  std::vector<bool> dropper_on, contact_on;
};

// K x = r of one active set, in triplets, with the scratch of eq. 12's contact weights.
struct StaticSystem {
  Triplets t;
  Eigen::VectorXd r;
  std::vector<int> node;
  std::vector<double> weight;
};

// The line: the wires' bands under their own weight and the clamp masses (Model::load), the
// supports' springs, and the taut droppers, each pulling with its design tension (the design
// shape is the state of zero displacement, eq. 23).
void add_line(const Model& m, const StaticUnknowns& q, const ActiveSet& active, StaticSystem& sys) {
  sys.r.head(m.n_dof) = m.load;
  for (std::size_t i = 0; i < m.wires.size(); ++i) add_wire_band(sys.t, m.wires[i], m.wires[i].w_dof, q.theta0[i]);
  for (const SupportSpring& s : m.springs) sys.t.emplace_back(s.dof, s.dof, s.static_stiffness());
  for (std::size_t k = 0; k < m.droppers.size(); ++k) {
    const Dropper& d = m.droppers[k];
    if (active.dropper_on[k]) add_spring(sys.t, sys.r, d.messenger_dof, d.contact_dof, d.stiffness, -d.static_tension);
  }
  for (const WireClamp& c : m.clamps) add_spring(sys.t, sys.r, c.upper_dof, c.lower_dof, c.stiffness, -c.static_force);
}

// A lumped pantograph's frame (eq. 9 at rest): the springs between its masses with their
// preloads, the roof spring unless left out, the uplift on the lowest mass and the heads on
// their suspensions with their own aerodynamic uplift.
void add_pantograph_frame(const Pantograph& p, double uplift, double air_speed_squared, bool roof_springs,
                          StaticSystem& sys) {
  for (int i = 0; i < p.masses_count(); ++i) {
    const bool roof = i + 1 == p.masses_count();
    if (roof && !roof_springs) continue;
    add_spring(sys.t, sys.r, p.first_dof + i, roof ? -1 : p.first_dof + i + 1, p.stiffness[i], p.spring_preload[i]);
  }
  sys.r[p.first_dof + p.masses_count() - 1] += uplift;
  for (const Head& h : p.heads) {
    add_spring(sys.t, sys.r, h.dof, p.first_dof, h.stiffness, h.preload);
    sys.r[h.dof] += h.aero_coefficient * air_speed_squared;
  }
}

// A force-driven collector at station xc, as in step(): its force `given` acts on the lowest
// contact wire(s) under it, shared equally among wires within 1 mm of the lowest.
void add_given_force(const Model& m, double xc, double given, StaticSystem& sys) {
  std::vector<double> yd(m.contact_wires.size(), std::numeric_limits<double>::infinity());
  double lowest = std::numeric_limits<double>::infinity();
  for (std::size_t wk = 0; wk < m.contact_wires.size(); ++wk) {
    const Wire& w = m.wires[m.contact_wires[wk]];
    const int cnt = contact_weights(w, m.rub_length, xc, sys.node.data(), sys.weight.data());
    if (cnt == 0) continue;
    yd[wk] = 0.0;
    for (int a = 0; a < cnt; ++a) yd[wk] += sys.weight[a] * w.height[sys.node[a]];
    lowest = std::min(lowest, yd[wk]);
  }
  int sharing = 0;
  for (double y : yd) sharing += y <= lowest + 1e-3;
  for (std::size_t wk = 0; wk < m.contact_wires.size(); ++wk) {
    if (!(yd[wk] <= lowest + 1e-3)) continue;
    const Wire& w = m.wires[m.contact_wires[wk]];
    const int cnt = contact_weights(w, m.rub_length, xc, sys.node.data(), sys.weight.data());
    for (int a = 0; a < cnt; ++a) sys.r[w.w_dof + sys.node[a]] += given / sharing * sys.weight[a];
  }
}

// Collector ci at station xc pressed on every contact wire under it that the active set keeps
// in touch: the contact spring k0 between the strip and the wire (eq. 22), whose gap at zero
// displacement is the strip's reference height less the wire's design height there (eq. 12).
void add_contact_springs(const Model& m, const Pantograph& p, int ci, double xc, const ActiveSet& active,
                         StaticSystem& sys) {
  for (std::size_t wk = 0; wk < m.contact_wires.size(); ++wk) {
    const Wire& w = m.wires[m.contact_wires[wk]];
    const int cnt = contact_weights(w, m.rub_length, xc, sys.node.data(), sys.weight.data());
    if (cnt == 0) continue;
    if (!active.contact_on[ci * m.contact_wires.size() + wk]) continue;
    double yd = 0.0;
    for (int a = 0; a < cnt; ++a) yd += sys.weight[a] * w.height[sys.node[a]];
    const double gap0 = p.contact_reference(m.collectors[ci]) - yd, k0 = m.contact_stiffness;
    const int h = m.collectors[ci].dof;
    sys.t.emplace_back(h, h, k0);
    sys.r[h] -= k0 * gap0;
    for (int a = 0; a < cnt; ++a) {
      const int ja = w.w_dof + sys.node[a];
      sys.t.emplace_back(h, ja, -k0 * sys.weight[a]);
      sys.t.emplace_back(ja, h, -k0 * sys.weight[a]);
      sys.r[ja] += k0 * sys.weight[a] * gap0;
      for (int b = 0; b < cnt; ++b) sys.t.emplace_back(ja, w.w_dof + sys.node[b], k0 * sys.weight[a] * sys.weight[b]);
    }
  }
}

// Every pantograph at the loads' train position: its frame, and each collector either pressed
// through its contact springs or, for a moving force or an external rig, pushing with its force.
void add_pantographs(const Model& m, const PantographLoads& loads, const ActiveSet& active, bool roof_springs,
                     StaticSystem& sys) {
  for (std::size_t pi = 0; pi < m.pantographs.size(); ++pi) {
    const Pantograph& p = m.pantographs[pi];
    const double uplift = loads.uplift[pi] + p.aero_coefficient * loads.air_speed_squared[pi];
    if (!p.moving_force) add_pantograph_frame(p, uplift, loads.air_speed_squared[pi], roof_springs, sys);
    for (std::size_t cj = 0; cj < p.collectors.size(); ++cj) {
      const int ci = p.collectors[cj];
      const double xc = loads.front - p.position + m.collectors[ci].offset;
      if (p.moving_force) {
        add_given_force(m, xc, (p.external ? loads.external_force[pi] : uplift) / p.collectors.size(), sys);
        continue;
      }
      add_contact_springs(m, p, ci, xc, active, sys);
    }
  }
}

// The rigid supports (no inverse mass) held at zero: identity rows and columns; then K x = r.
Eigen::VectorXd solve_held(const Model& m, int size, StaticSystem& sys, SpdSolver& solver) {
  std::vector<bool> fixed(size, false);
  for (int i = 0; i < m.n_dof; ++i) fixed[i] = m.inv_mass[i] == 0.0;
  Triplets tr;
  tr.reserve(sys.t.size() + static_cast<std::size_t>(size));
  for (const auto& e : sys.t)
    if (!fixed[e.row()] && !fixed[e.col()]) tr.push_back(e);
  for (int i = 0; i < size; ++i)
    if (fixed[i]) {
      tr.emplace_back(i, i, 1.0);
      sys.r[i] = 0.0;
    }
  Eigen::SparseMatrix<double> k(size, size);
  k.setFromTriplets(tr.begin(), tr.end());
  return solver.solve(k, sys.r, "the initial configuration (eq. 23)");
}

// Eq. 25 on the solution x: a dropper is taut while its tension S0 + k (w_messenger - w_contact)
// is positive. True if any dropper changed.
bool update_taut_droppers(const Model& m, const Eigen::VectorXd& x, ActiveSet& active) {
  bool changed = false;
  for (std::size_t k = 0; k < m.droppers.size(); ++k) {
    const Dropper& d = m.droppers[k];
    const bool on = d.static_tension + d.stiffness * (x[d.messenger_dof] - x[d.contact_dof]) > 0.0;
    if (on != active.dropper_on[k]) changed = true;
    active.dropper_on[k] = on;
  }
  return changed;
}

// Eq. 25 on the solution x: a collector presses on a contact wire while its strip is not below
// the wire under it (eq. 12). True if any contact changed.
bool update_contacts(const Model& m, const PantographLoads& loads, const Eigen::VectorXd& x, ActiveSet& active,
                     StaticSystem& sys) {
  bool changed = false;
  for (std::size_t ci = 0; ci < m.collectors.size(); ++ci) {
    const Pantograph& p = m.pantographs[m.collectors[ci].pantograph];
    if (p.moving_force) continue;
    const double xc = loads.front - p.position + m.collectors[ci].offset;
    for (std::size_t wk = 0; wk < m.contact_wires.size(); ++wk) {
      const Wire& w = m.wires[m.contact_wires[wk]];
      const int cnt = contact_weights(w, m.rub_length, xc, sys.node.data(), sys.weight.data());
      double yw = 0.0;
      for (int a = 0; a < cnt; ++a) yw += sys.weight[a] * (w.height[sys.node[a]] + x[w.w_dof + sys.node[a]]);
      const Collector& col = m.collectors[ci];
      const bool on = cnt > 0 && p.contact_reference(col) + x[col.dof] - yw >= 0.0;
      const std::size_t idx = ci * m.contact_wires.size() + wk;
      if (on != active.contact_on[idx]) changed = true;
      active.contact_on[idx] = on;
    }
  }
  return changed;
}

}  // namespace

PantographLoads design_pantograph_loads(const Model& m) {
  PantographLoads loads;
  loads.front = m.train_start;
  for (const Pantograph& p : m.pantographs) loads.uplift.push_back(p.static_uplift);
  loads.external_force = loads.uplift;
  const double v = m.scene.train_speed;
  loads.air_speed_squared.assign(m.pantographs.size(), v * v);
  return loads;
}

Eigen::VectorXd solve_static_equilibrium(const Model& m, const PantographLoads& loads, bool roof_springs) {
  const StaticUnknowns q = static_unknowns(m);
  ActiveSet active;
  active.dropper_on.assign(m.droppers.size(), true);
  active.contact_on.assign(m.collectors.size() * m.contact_wires.size(), true);
  StaticSystem sys;
  // The active set changes values, seldom the pattern; and a model's two solves (the pantographs'
  // references without roof springs, then the initial state) mostly share one: the ordering of
  // the last pattern solved in this thread is kept (SpdSolver compares the whole pattern, so
  // another model's matrix is ordered afresh; the factors a kept ordering gives are the same).
  thread_local SpdSolver solver;
  // Room for every iteration's triplets at once (clear() keeps it): add_wire_band's 4 a node and
  // 8 an element, a spring's 4, the contact springs' (nodes + 2)^2 per collector and wire.
  std::size_t room = 4 * (m.springs.size() + m.droppers.size()) + 64 * m.pantographs.size();
  for (const Wire& w : m.wires) room += 12 * static_cast<std::size_t>(w.nodes());
  const std::size_t patch = static_cast<std::size_t>(m.max_contact_nodes) + 2;
  room += patch * patch * m.collectors.size() * m.contact_wires.size();
  sys.t.reserve(room);
  sys.node.resize(m.max_contact_nodes);
  sys.weight.resize(m.max_contact_nodes);
  // The active set is guessed, solved for, and corrected until it agrees with its solution.
  for (int iter = 0; iter < 60; ++iter) {
    sys.t.clear();
    sys.r = Eigen::VectorXd::Zero(q.size);
    add_line(m, q, active, sys);
    add_pantographs(m, loads, active, roof_springs, sys);
    const Eigen::VectorXd x = solve_held(m, q.size, sys, solver);
    const bool droppers_changed = update_taut_droppers(m, x, active);
    const bool contacts_changed = update_contacts(m, loads, x, active, sys);
    if (!droppers_changed && !contacts_changed) return x.head(m.n_dof);
  }
  throw SceneError("statics: the initial configuration (eq. 23) found no consistent set of slack droppers and "
                   "contacts in 60 iterations; check static_uplift and the dropper data");
}

void set_pantograph_references(Model& m) {
  // Displacement 0 of a pantograph puts its head at the design height of the contact wire under
  // its collectors at the start; the springs between masses carry the static uplift there, so at
  // the static state every mass is displaced as much as the head. The roof spring is relaxed at
  // the initial static state: the static uplift is then exactly the static contact force, and the
  // roof spring models how that force changes with working height.
  for (Pantograph& p : m.pantographs) {
    double sum = 0.0;
    int count = 0;
    for (int ci : p.collectors) {
      // The lowest contact wire over the collector is the one the head meets first.
      const double lowest = lowest_design_height(m, m.train_start - p.position + m.collectors[ci].offset);
      if (std::isfinite(lowest)) {
        sum += lowest;
        ++count;
      }
    }
    p.reference_height = count ? sum / count : m.scene.contact_wire_height;
    p.spring_preload.assign(p.masses.size(), p.static_uplift);
    if (!p.masses.empty()) p.spring_preload.back() = 0.0;
    // Each head likewise at the wire over its own strips, its suspension carrying its strips'
    // share of the static uplift (the initial statics then settle the split, eq. 23).
    for (Head& h : p.heads) {
      double hs = 0.0;
      int hc = 0;
      for (int ci : h.collectors) {
        const double lowest = lowest_design_height(m, m.train_start - p.position + m.collectors[ci].offset);
        if (std::isfinite(lowest)) {
          hs += lowest;
          ++hc;
        }
      }
      h.reference_height = hc ? hs / hc : p.reference_height;
      h.preload = p.static_uplift * static_cast<double>(h.collectors.size()) / static_cast<double>(p.collectors.size());
    }
  }
  if (m.pantographs.empty()) return;
  Eigen::VectorXd u;
  try {
    u = solve_static_equilibrium(m, design_pantograph_loads(m), false);
  } catch (const SceneError&) {
    // Without roof springs (relaxed at the working height, eq. 23) only the contact holds a
    // lumped pantograph: with no uplift it may not press on the wire, and nothing holds it.
    for (std::size_t i = 0; i < m.pantographs.size(); ++i) {
      const Pantograph& p = m.pantographs[i];
      const double v = m.scene.train_speed;
      double uplift = p.static_uplift + p.aero_coefficient * v * v;
      for (const Head& h : p.heads) uplift += h.aero_coefficient * v * v;
      if (!p.moving_force && !(uplift > 0.0)) {
        std::ostringstream s;
        s << "scene field 'pantographs[" << i << "].static_uplift' = " << p.static_uplift
          << ": allowed > 0 N in this scene: the initial statics (eq. 23) hold pantograph '" << p.name
          << "' at its working height by its contact alone (the roof spring is relaxed there), and with an uplift of "
          << uplift << " N it does not press on the wire at the start";
        throw SceneError(s.str());
      }
    }
    throw;
  }
  for (Pantograph& p : m.pantographs) {
    if (p.moving_force) continue;
    const int last = p.masses_count() - 1;
    p.spring_preload[last] = p.stiffness[last] * u[p.first_dof + last];
  }
}

}  // namespace catenary_sim

namespace catenary_sim {

namespace {

Scene probe_scene(const Scene& scene, double force) {
  Scene s = scene;
  PantographSpec p;
  p.name = "probe";
  p.masses = {1.0};
  p.stiffness = {0.0};
  p.damping = {0.0};
  p.static_uplift = force;
  p.collectors = {CollectorSpec{}};
  s.pantographs = {p};
  s.train_speed = 0.0;
  s.train_start.reset();
  s.train_end.reset();
  s.contact.rub_length = 0.0;  // a point load: the elasticity at the station itself
  return s;
}

// The probe's (collector 0's) contact force on contact wire k at displacements u with the train
// at `front`: eq. 22 with eq. 25, max(0, k0 (head - wire)), as the engine observes it.
double probe_contact_force(const Model& m, const Eigen::VectorXd& u, double front, std::size_t k, int* node,
                           double* weight) {
  const Collector& col = m.collectors[0];
  const Pantograph& p = m.pantographs[col.pantograph];
  const double head = p.contact_reference(col) + u[col.dof];
  const double xc = front - p.position + col.offset;
  const Wire& w = m.wires[m.contact_wires[k]];
  const int cnt = contact_weights(w, m.rub_length, xc, node, weight);
  if (cnt == 0) return 0.0;
  double yw = 0.0;
  for (int a = 0; a < cnt; ++a) yw += weight[a] * (w.height[node[a]] + u[w.w_dof + node[a]]);
  return std::max(0.0, m.contact_stiffness * (head - yw));
}

}  // namespace

ElasticityProbe::ElasticityProbe(const Scene& scene, double force, const std::optional<std::vector<double>>& rises) {
  BuildOptions o;
  o.stability = false;
  o.support_rises = rises;
  model_ = build_model(probe_scene(scene, force), o);
}

std::vector<double> ElasticityProbe::uplift(double x) const {
  const Model& m = model_;
  std::vector<double> out(m.contact_wires.size(), std::nan(""));
  PantographLoads loads = design_pantograph_loads(m);
  loads.front = x;
  Eigen::VectorXd u;
  try {
    u = solve_static_equilibrium(m, loads, true);
  } catch (const SceneError&) {
    return out;  // nothing under the probe to press against
  }
  std::vector<int> node(m.max_contact_nodes);
  std::vector<double> weight(m.max_contact_nodes);
  for (std::size_t k = 0; k < m.contact_wires.size(); ++k) {
    if (!(probe_contact_force(m, u, x, k, node.data(), weight.data()) > 0.0)) continue;
    const Wire& w = m.wires[m.contact_wires[k]];
    const int cnt = contact_weights(w, 0.0, x, node.data(), weight.data());
    double uplift = 0.0;
    for (int a = 0; a < cnt; ++a) uplift += weight[a] * u[w.w_dof + node[a]];
    out[k] = uplift;
  }
  return out;
}

std::vector<double> transition_support_rises(const Scene& scene) {
  const std::size_t ns = scene.sections.size();
  std::vector<double> rises(2 * ns, 0.0);
  bool any = false;
  for (const SectionSpec& sec : scene.sections) any = any || sec.first_span_transition || sec.last_span_transition;
  if (!any) return rises;
  if (scene.overlap && scene.overlap->support_rise) {
    for (std::size_t i = 0; i < ns; ++i) {
      rises[2 * i] = scene.sections[i].first_span_transition ? *scene.overlap->support_rise : 0.0;
      rises[2 * i + 1] = scene.sections[i].last_span_transition ? *scene.overlap->support_rise : 0.0;
    }
    return rises;
  }
  // F of eq. 6: the design force, else the mean static uplift of the pantographs, else 100 N.
  double force = 100.0;
  if (scene.overlap && scene.overlap->design_force) {
    force = *scene.overlap->design_force;
  } else if (!scene.pantographs.empty()) {
    force = 0.0;
    for (const PantographSpec& p : scene.pantographs) force += p.static_uplift;
    force /= scene.pantographs.size();
  }
  if (!(force > 0.0))
    throw SceneError("scene field 'overlap.design_force' = (missing): the pantographs' mean static_uplift is " + fmt(force) +
                     " N, and eq. 6 derives the support rise from the uplift under a force > 0: give overlap.design_force "
                     "(N) or overlap.support_rise (m)");
  // E at mid-span of a current span, measured on the model with the supports not yet raised.
  const ElasticityProbe probe(scene, force, std::vector<double>(2 * ns, 0.0));
  for (std::size_t i = 0; i < ns; ++i) {
    const SectionSpec& sec = scene.sections[i];
    const int n = static_cast<int>(sec.spans.size());
    int best = -1;
    double best_dist = 1e300, x0 = sec.start;
    std::vector<double> starts;
    for (int j = 0; j < n; ++j) {
      starts.push_back(x0);
      const bool transition = (j == 0 && sec.first_span_transition) || (j == n - 1 && sec.last_span_transition);
      const double dist = std::fabs(x0 + 0.5 * sec.spans[j] - (sec.start + 0.5 * sec.length()));
      if (!transition && dist < best_dist) {
        best = j;
        best_dist = dist;
      }
      x0 += sec.spans[j];
    }
    if (best < 0) best = n / 2;  // no current span: the middle span, supports not raised
    const std::vector<double> up = probe.uplift(starts[best] + 0.5 * sec.spans[best]);
    double h = 0.0;
    for (std::size_t k = 0; k < up.size(); ++k)
      if (probe.model().wires[probe.model().contact_wires[k]].section == static_cast<int>(i) && std::isfinite(up[k]))
        h = std::max(h, up[k]);
    if (!(h > 0.0))
      throw SceneError("overlap: the static uplift under " + fmt(force) + " N at mid-span of span " +
                       std::to_string(best) + " of section " + std::to_string(i) +
                       " could not be measured (eq. 6); give overlap.support_rise");
    const double p = sec.contact_wire.linear_mass * scene.gravity, T = sec.contact_wire.tension;
    const double b = std::sqrt(2.0 * T * h / p);  // eq. 7
    auto rise = [&](double span) {
      const double a = 0.5 * span;
      return p * (a + 0.5 * b) * (a + 0.5 * b) / (2.0 * T);  // eq. 8
    };
    if (sec.first_span_transition) rises[2 * i] = rise(sec.spans.front());
    if (sec.last_span_transition) rises[2 * i + 1] = rise(sec.spans.back());
  }
  return rises;
}

}  // namespace catenary_sim
