// Building the model from a scene, element by element of the line: the meshed wires and the DOF
// layout, the pantographs, the lumped masses and supports, the droppers, the design statics, the
// constant load, the train's travel and the time step.
#include "catenary_sim/core/model/build_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

#include "catenary_sim/core/model/beam.hpp"
#include "catenary_sim/core/model/lateral.hpp"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/model/stability.hpp"
#include "catenary_sim/core/model/statics.hpp"
#include "catenary_sim/core/model/wire_band.hpp"
#include "model/centred_factors.hpp"
#include "model/design_statics.hpp"
#include "model/endless_block.hpp"
#include "model/imperfections.hpp"
#include "model/newmark_matrix.hpp"
#include "model/wire_packs.hpp"
#include "util/format.hpp"

namespace catenary_sim {
namespace {

// Two stations of a wire closer than this are refused: a dropper's or a clamp's fitting is a few
// centimetres long, so closer ones cannot both be built, and the element between them would cut
// dt by the square of its share of numerics.element_length and load the statics with stiffnesses
// of its cube (at 5 um, garbage). Stations closer than 1e-9 m are one node.
constexpr double kClosestStations = 0.01;  // m

// Node stations of one tension section: every support and dropper is a node; the segments
// between them are split into equal elements no longer than the requested length.
std::vector<double> mesh_section(const Scene& scene, std::size_t si, std::vector<double>& support_x) {
  const SectionSpec& sec = scene.sections[si];
  const double element_length = scene.numerics.element_length;
  struct Station {
    double x;
    const char* what;  // the scene field that put it there
    double given;      // its value there (a position in the span, a length)
  };
  std::vector<Station> breaks;
  double x0 = sec.start;
  support_x.assign(1, x0);
  const std::size_t nspan = sec.spans.size();
  for (std::size_t i = 0; i < nspan; ++i) {
    const std::size_t first = breaks.size();
    breaks.push_back({x0, "spans", sec.spans[i]});
    if (sec.droppers)
      for (double p : sec.droppers->positions[i]) breaks.push_back({x0 + p, "droppers.positions", p});
    if (sec.hangers)  // a compound line's
      for (double p : sec.hangers->positions[i]) breaks.push_back({x0 + p, "hangers.positions", p});
    if (sec.stitch_wire) {  // the clamps of the stitch wires at the span's intermediate supports
      const StitchWireSpec& st = *sec.stitch_wire;
      const char* what = st.lengths.empty() ? "stitch_wire.length" : "stitch_wire.lengths";
      const int a = static_cast<int>(i), b = a + 1;
      if (i > 0 && st.at(a)) breaks.push_back({x0 + 0.5 * st.length_at(a), what, st.length_at(a)});
      if (i + 1 < nspan && st.at(b)) breaks.push_back({x0 + sec.spans[i] - 0.5 * st.length_at(b), what, st.length_at(b)});
    }
    if (sec.bridle) {  // the clamps of the bridles at the span's intermediate supports
      const double half = 0.5 * sec.bridle->length;
      if (i > 0) breaks.push_back({x0 + half, "bridle.length", sec.bridle->length});
      if (i + 1 < nspan) breaks.push_back({x0 + sec.spans[i] - half, "bridle.length", sec.bridle->length});
    }
    if (sec.hangers || sec.stitch_wire || sec.bridle) {  // (droppers alone are in order: validate_sections)
      const auto from = breaks.begin() + static_cast<std::ptrdiff_t>(first);
      std::stable_sort(from, breaks.end(), [](const Station& a, const Station& b) { return a.x < b.x; });
      breaks.erase(std::unique(from, breaks.end(), [](const Station& a, const Station& b) { return b.x - a.x < 1e-9; }),
                   breaks.end());
    }
    x0 += sec.spans[i];
    support_x.push_back(x0);
  }
  breaks.push_back({x0, "spans", 0.0});
  for (std::size_t i = 0; i + 1 < breaks.size(); ++i) {
    const Station &a = breaks[i], &b = breaks[i + 1];
    if (b.x - a.x > kClosestStations - 1e-9) continue;  // (1 cm as given, less the stations' rounding)
    // (A support stays: what came near it is what to move.)
    const bool b_support = std::strcmp(b.what, "spans") == 0;
    const Station &moved = b_support ? a : b, &other = b_support ? b : a;
    const std::string near =
        std::strcmp(other.what, "spans") == 0 ? "the support" : "a station of '" + scene.section_field(si, other.what) + "'";
    throw SceneError("scene field '" + scene.section_field(si, moved.what) + "' = " + fmt_given(moved.given) +
                     " m puts a station at " + fmt_given(moved.x) + " m, " + fmt(b.x - a.x) + " m from " + near + " at " +
                     fmt_given(other.x) + " m: stations at least " + fmt(kClosestStations) +
                     " m apart (a dropper's or a clamp's fitting), or at the same station");
  }
  std::vector<double> x;
  for (std::size_t i = 0; i + 1 < breaks.size(); ++i) {
    const double len = breaks[i + 1].x - breaks[i].x;
    const int n = std::max(1, static_cast<int>(std::ceil(len / element_length - 1e-9)));
    for (int k = 0; k < n; ++k) x.push_back(breaks[i].x + len * k / n);
  }
  x.push_back(x0);
  return x;
}

int node_at(const std::vector<double>& x, double xs) {
  const auto it = std::lower_bound(x.begin(), x.end(), xs - 1e-9);
  return static_cast<int>(it - x.begin());
}

int line_support_index(const Model& m, double xs) {
  return static_cast<int>(std::lower_bound(m.support_x.begin(), m.support_x.end(), xs - 1e-9) - m.support_x.begin());
}

// A Scene filled in code with the one-section fields only.
void add_single_section(Scene& scene) {
  SectionSpec sec;
  sec.spans = scene.spans;
  sec.contact_wire = scene.contact_wire;
  sec.messenger = scene.messenger;
  sec.droppers = scene.droppers;
  sec.steady_arms = scene.steady_arms;
  sec.messenger_supports = scene.messenger_supports;
  sec.stitch_wire = scene.stitch_wire;
  sec.bridle = scene.bridle;
  sec.auxiliary_messenger = scene.auxiliary_messenger;
  sec.hangers = scene.hangers;
  if (sec.hangers && sec.hangers->positions.size() == 1 && sec.spans.size() > 1)
    sec.hangers->positions.assign(sec.spans.size(), sec.hangers->positions.front());
  if (sec.droppers && sec.droppers->positions.size() == 1 && sec.spans.size() > 1)
    sec.droppers->positions.assign(sec.spans.size(), sec.droppers->positions.front());
  scene.sections.push_back(sec);
}

// Raised contact-wire supports at the transition spans (eq. 6-8): given, measured, or none yet.
void support_rises(const Scene& scene, const BuildOptions& options, std::vector<double>& rise_first,
                   std::vector<double>& rise_last) {
  rise_first.assign(scene.sections.size(), 0.0);
  rise_last.assign(scene.sections.size(), 0.0);
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
}

// A short wire over the section's stations from `from` to `to` (mesh_section puts nodes at its
// ends), clamped there to another wire: a stitch wire (no supports of its own), or a trolley wire's
// bridle (`middle`: the station where its support holds it).
void add_clamped_wire(const std::string& name, int section, const WireSpec& spec, const std::vector<double>& x, double from,
                      double to, std::optional<double> middle, bool lumped_rot, Model& m, int& dof, Section& info) {
  const int lo = node_at(x, from), hi = node_at(x, to);
  Wire w;
  w.name = name;
  w.section = section;
  w.is_clamped_wire = true;  // (a bridle too: a short wire between two clamps, which the window and the packs take alike)
  w.is_bridle = middle.has_value();
  w.spec = spec;
  w.x.assign(x.begin() + lo, x.begin() + hi + 1);
  if (middle) w.support_nodes.push_back(node_at(w.x, *middle));
  w.w_dof = dof;
  dof += w.nodes();
  if (lumped_rot) {
    w.theta_dof = dof;
    dof += w.nodes();
  }
  assemble_band(w, {});
  info.clamped_wires.push_back(static_cast<int>(m.wires.size()));
  m.wires.push_back(std::move(w));
}

WireSpec wire_spec(double linear_mass, double bending_stiffness, double tension) {
  WireSpec spec;
  spec.linear_mass = linear_mass;
  spec.bending_stiffness = bending_stiffness;
  spec.tension = tension;
  return spec;
}

// A stitch wire at each intermediate support of a section that carries one.
void add_stitch_wires(const StitchWireSpec& st, int section, const std::vector<double>& supports,
                      const std::vector<double>& x, bool lumped_rot, const std::string& suffix, Model& m, int& dof,
                      Section& info) {
  const WireSpec spec = wire_spec(st.linear_mass, st.bending_stiffness, st.tension);
  for (std::size_t k = 1; k + 1 < supports.size(); ++k) {
    if (!st.at(static_cast<int>(k))) continue;  // held as on a simple line
    const double half = 0.5 * st.length_at(static_cast<int>(k));
    add_clamped_wire("stitch_wire" + suffix + "_" + std::to_string(k), section, spec, x, supports[k] - half,
                     supports[k] + half, std::nullopt, lumped_rot, m, dof, info);
  }
}

// A trolley wire's bridle at each intermediate support of a section, held at its middle there.
void add_bridles(const BridleSpec& b, int section, const std::vector<double>& supports, const std::vector<double>& x,
                 bool lumped_rot, const std::string& suffix, Model& m, int& dof, Section& info) {
  const WireSpec spec = wire_spec(b.linear_mass, b.bending_stiffness, b.tension);
  for (std::size_t k = 1; k + 1 < supports.size(); ++k)
    add_clamped_wire("bridle" + suffix + "_" + std::to_string(k), section, spec, x, supports[k] - 0.5 * b.length,
                     supports[k] + 0.5 * b.length, supports[k], lumped_rot, m, dof, info);
}

// DOF layout: per wire the vertical displacements, then (lumped rotary inertia only) the
// rotations; section by section (contact wire(s), messenger, stitch wires or the auxiliary
// messenger); the pantographs last.
void mesh_wires(const Scene& scene, const std::vector<double>& rise_first, const std::vector<double>& rise_last,
                Model& m, int& dof, std::vector<std::vector<double>>& section_supports) {
  const bool lumped_rot = scene.numerics.rotary_inertia == RotaryInertia::kLumped;
  for (std::size_t si = 0; si < scene.sections.size(); ++si) {
    const SectionSpec& sec = scene.sections[si];
    const std::vector<double> x = mesh_section(scene, si, section_supports[si]);
    Section info;
    info.start = sec.start;
    info.end = sec.end();
    info.rise_first = rise_first[si];
    info.rise_last = rise_last[si];
    const std::string suffix = scene.sections.size() > 1 ? "_s" + std::to_string(si) : "";
    auto add_wire = [&](const std::string& name, const WireSpec& spec, bool contact, bool auxiliary = false) {
      Wire w;
      w.name = name;
      w.section = static_cast<int>(si);
      w.is_contact_wire = contact;
      w.is_auxiliary_messenger = auxiliary;
      w.spec = spec;
      w.x = x;
      w.w_dof = dof;
      dof += static_cast<int>(x.size());
      if (lumped_rot) {
        w.theta_dof = dof;
        dof += static_cast<int>(x.size());
      }
      for (double sx : section_supports[si]) w.support_nodes.push_back(node_at(x, sx));
      assemble_band(w, transition_piece_factors(scene, w));
      if (auxiliary) {  // (not among info.wires, which the droppers hold or hang from)
        info.auxiliary = static_cast<int>(m.wires.size());
        m.wires.push_back(std::move(w));
        return;
      }
      if (contact) m.contact_wires.push_back(static_cast<int>(m.wires.size()));
      else info.messenger = static_cast<int>(m.wires.size());
      info.wires.push_back(static_cast<int>(m.wires.size()));
      m.wires.push_back(std::move(w));
    };
    for (int c = 0; c < sec.contact_wire_count; ++c)
      add_wire("contact_wire" + suffix + (sec.contact_wire_count > 1 ? std::string(1, static_cast<char>('a' + c)) : ""),
               sec.contact_wire, true);
    if (sec.messenger) add_wire("messenger" + suffix, *sec.messenger, false);
    if (sec.auxiliary_messenger) add_wire("auxiliary_messenger" + suffix, *sec.auxiliary_messenger, false, true);
    if (sec.stitch_wire) add_stitch_wires(*sec.stitch_wire, static_cast<int>(si), section_supports[si], x, lumped_rot, suffix, m, dof, info);
    if (sec.bridle) add_bridles(*sec.bridle, static_cast<int>(si), section_supports[si], x, lumped_rot, suffix, m, dof, info);
    m.sections.push_back(info);
  }
}

// Pantographs: the chain's masses, then each head's, after the catenary's DOFs; their collectors.
void add_pantographs(const Scene& scene, Model& m, int& dof) {
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
}

// Returns which DOFs are held rigidly.
std::vector<bool> lump_masses(const Scene& scene, Model& m) {
  const int dof = m.n_dof;
  const bool lumped_rot = scene.numerics.rotary_inertia == RotaryInertia::kLumped;
  // Lumped masses (HRZ for the beams) and which DOFs are held rigidly: the anchors at both ends
  // of each section, and intermediate supports without a spring.
  m.mass = Eigen::VectorXd::Zero(dof);
  std::vector<bool> fixed(dof, false);
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
    const bool contact = w.is_contact_wire || w.is_bridle;  // (a bridle: the contact wire's suspension)
    const std::optional<SupportSpec>& spring = contact ? sec.steady_arms : sec.messenger_supports;
    const int ns = static_cast<int>(w.support_nodes.size());
    for (int k = 0; k < ns; ++k) {
      const int node = w.support_nodes[k];
      const bool end = !w.is_bridle && (k == 0 || k == ns - 1);  // anchors of the tension section
      if (!end && w.is_auxiliary_messenger) continue;  // free through the supports, hung by droppers
      if (!end && w.is_contact_wire && sec.bridle) continue;  // hung from the bridle's clamps
      if (end || !spring) {
        fixed[w.w_dof + node] = true;
      } else {
        m.mass[w.w_dof + node] += spring->mass;
        SupportSpring sp{w.w_dof + node, spring->stiffness, 0.0, w.x[node], line_support_index(m, w.x[node]), contact};
        sp.section_support = k;
        m.springs.push_back(sp);
      }
    }
  }
  return fixed;
}

// The wire a dropper at station xd hangs from: the stitch wire whose clamps it lies strictly
// between, else the messenger; and its node there.
std::pair<const Wire*, int> dropper_top(const Model& m, const Section& info, double xd) {
  for (int wi : info.clamped_wires) {
    const Wire& w = m.wires[wi];
    if (xd > w.x.front() + 1e-9 && xd < w.x.back() - 1e-9) return {&w, node_at(w.x, xd)};
  }
  const Wire& mwire = m.wires[info.messenger];
  return {&mwire, node_at(mwire.x, xd)};
}

// Each short clamped wire's two clamps, the clamp masses on its ends (the clamp is one body; on the
// lighter node it keeps the clamp's own frequency low): a stitch wire hangs from the messenger, a
// bridle holds the contact wire below it. Their static forces come from the design statics.
void clamp_short_wires(const Scene& scene, Model& m) {
  for (std::size_t si = 0; si < scene.sections.size(); ++si) {
    const SectionSpec& sec = scene.sections[si];
    const Section& info = m.sections[si];
    if (!sec.stitch_wire && !sec.bridle) continue;
    const bool bridle = sec.bridle.has_value();  // (never both: a stitch wire needs a messenger, a bridle refuses one)
    const Wire& other = m.wires[bridle ? info.wires.front() : info.messenger];  // (a bridle's: the one contact wire)
    const double clamp_mass = bridle ? sec.bridle->clamp_mass : sec.stitch_wire->clamp_mass;
    for (int wi : info.clamped_wires) {
      const Wire& w = m.wires[wi];
      for (int end : {0, w.nodes() - 1}) {
        WireClamp c;
        c.x = w.x[end];
        const int own = w.w_dof + end, held = other.w_dof + node_at(other.x, c.x);
        c.upper_dof = bridle ? own : held;  // the upper node
        c.lower_dof = bridle ? held : own;  // the lower node
        c.stiffness = kWireClampStiffness;
        m.mass[own] += clamp_mass;
        m.clamps.push_back(c);
      }
    }
  }
}

void hang_droppers(const Scene& scene, const std::vector<std::vector<double>>& section_supports, Model& m) {
  // Droppers: one per contact wire at each dropper station (a twin contact wire hangs both wires
  // from the same dropper), with clamp masses; lengths and tensions come from the design statics.
  // A compound line's droppers hold its auxiliary messenger, and its hangers the contact wire
  // from the auxiliary.
  auto hang = [&](int section, int span, double xd, const DropperSpec& ds, const Wire& top, int top_node, const Wire& low,
                  bool hanger) {
    Dropper d;
    d.x = xd;
    d.section = section;
    d.span = span;
    d.hanger = hanger;
    d.contact_dof = low.w_dof + node_at(low.x, xd);
    d.messenger_dof = top.w_dof + top_node;
    m.mass[d.contact_dof] += ds.clamp_mass_contact;
    m.droppers.push_back(d);
  };
  for (std::size_t si = 0; si < scene.sections.size(); ++si) {
    const SectionSpec& sec = scene.sections[si];
    if (!sec.droppers) continue;
    const Section& info = m.sections[si];
    const DropperSpec& ds = *sec.droppers;
    const int section = static_cast<int>(si);
    for (std::size_t i = 0; i < sec.spans.size(); ++i)
      for (double p : ds.positions[i]) {
        const double xd = section_supports[si][i] + p;
        const auto [top, top_node] = dropper_top(m, info, xd);
        m.mass[top->w_dof + top_node] += ds.clamp_mass_messenger;
        if (info.auxiliary >= 0) {
          hang(section, static_cast<int>(i), xd, ds, *top, top_node, m.wires[info.auxiliary], false);
          continue;
        }
        for (int wi : info.wires)
          if (wi != info.messenger) hang(section, static_cast<int>(i), xd, ds, *top, top_node, m.wires[wi], false);
      }
    if (!sec.hangers) continue;
    const Wire& aux = m.wires[info.auxiliary];
    for (std::size_t i = 0; i < sec.spans.size(); ++i)
      for (double p : sec.hangers->positions[i]) {
        const double xh = section_supports[si][i] + p;
        const int top_node = node_at(aux.x, xh);
        m.mass[aux.w_dof + top_node] += sec.hangers->clamp_mass_messenger;
        for (int wi : info.wires)
          if (wi != info.messenger) hang(section, static_cast<int>(i), xh, *sec.hangers, aux, top_node, m.wires[wi], true);
      }
  }
}

void set_constant_load(const Scene& scene, Model& m, const std::vector<bool>& fixed) {
  const int dof = m.n_dof;
  const double g = scene.gravity;
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
}

void set_pantograph_masses(Model& m) {
  // Pantographs: unit-less references are set by the initial statics in the Simulation.
  // The most nodes a contact patch (rub_length wide) can cover on a wire the collectors touch: the
  // most stations within rub_length of one another, and one more on each side.
  int max_nodes = 2;
  if (m.rub_length > 0.0)
    for (int wi : m.contact_wires) {
      const std::vector<double>& x = m.wires[wi].x;
      for (std::size_t lo = 0, hi = 0; hi < x.size(); ++hi) {
        while (x[hi] - x[lo] > m.rub_length) ++lo;
        max_nodes = std::max(max_nodes, static_cast<int>(hi - lo + 1) + 3);
      }
    }
  m.max_contact_nodes = max_nodes;
  for (Pantograph& p : m.pantographs)
    if (!p.moving_force) {  // a moving force set in code may keep masses it does not use (no DOFs)
      for (int i = 0; i < p.masses_count(); ++i) m.mass[p.first_dof + i] = p.masses[i];
      for (const Head& h : p.heads) m.mass[h.dof] = h.mass;
    }
}

void set_inverse_mass(Model& m, const std::vector<bool>& fixed) {
  const int dof = m.n_dof;
  m.inv_mass = Eigen::VectorXd::Zero(dof);
  for (int i = 0; i < dof; ++i) {
    if (fixed[i]) continue;
    if (!(m.mass[i] > 0.0))
      throw SceneError("model: DOF " + std::to_string(i) + " has no mass; check linear_mass and masses");
    m.inv_mass[i] = 1.0 / m.mass[i];
  }
}

// The wave speed and its warning, the longest span, and the droppers and supports in line order.
void set_line_order(const Scene& scene, Model& m) {
  m.window_holds_sections =
      scene.numerics.windowed() && std::any_of(scene.sections.begin(), scene.sections.end(),
                                               [](const SectionSpec& sec) { return sec.rigid || sec.bridle.has_value(); });
  m.wave_speed = 1e300;
  for (int wi : m.contact_wires)
    if (!scene.sections[m.wires[wi].section].rigid)  // a tension-free profile: no string wave, no such limit
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
  for (std::size_t k = 0; k < m.clamps.size(); ++k) m.clamp_order.push_back(static_cast<int>(k));
  std::stable_sort(m.clamp_order.begin(), m.clamp_order.end(), [&](int a, int b) { return m.clamps[a].x < m.clamps[b].x; });
  for (int k : m.clamp_order) m.clamp_order_x.push_back(m.clamps[k].x);
}

void set_train_travel(const Scene& scene, double endless_front, Model& m) {
  // Train travel: by default from the rearmost collector at the line start to the foremost at
  // the line end.
  double lead = 0.0, rear = 0.0;
  collector_extent(scene, &lead, &rear);
  m.train_start = scene.train_start ? *scene.train_start : -rear;
  m.train_end = scene.train_end ? *scene.train_end : m.line_length - lead;
  if (m.endless) {
    check_endless_block(m);
    if (!(m.train_end > endless_front))
      throw SceneError("scene field 'train.end' = " + fmt(m.train_end) + ": allowed beyond " + fmt(endless_front + 0.0) +
                       " m, the train front's station at the start of the pass");
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
      throw SceneError("scene field 'train.end' = " + fmt(m.train_end) + ": allowed >= train.start (" +
                       fmt(m.train_start + 0.0) + " m)");  // (+ 0.0: a start of -0 shows as 0)
    // Every pantograph passes through some of the analysis section, or its statistics are empty.
    double x0 = 0.0, x1 = 0.0;
      x0 = m.support_x[scene.analysis_first()];
    x1 = m.support_x[scene.analysis_last()];
    for (const PantographSpec& p : scene.pantographs) {
      // (At its start or end exactly, it would pass none of it: one sample, no statistics.)
      if (m.train_end - p.position <= x0)
        throw SceneError("scene field 'train.end' = " + fmt_given(m.train_end) + ": pantograph '" + p.name +
                         "' would stop before running through the analysis section " + fmt(x0) + "-" + fmt(x1) +
                         " m (output.analysis_spans); allowed > " + fmt(x0 + p.position) + " m");
      if (m.train_start - p.position >= x1)
        throw SceneError("scene field 'train.start' = " + fmt_given(m.train_start) + ": pantograph '" + p.name +
                         "' would start after the analysis section " + fmt(x0) + "-" + fmt(x1) +
                         " m (output.analysis_spans); allowed < " + fmt(x1 + p.position) + " m");
    }
  }
}

// numerics.supports / numerics.droppers implicit: which support springs, droppers and stitch wires'
// clamps the explicit step takes at its middle (Model::support_at_middle, dropper_at_middle,
// clamp_at_middle), each a closed-form correction of its nodes' update (explicit_step.cpp). A
// support on a free node that no other support shares; a dropper or clamp with a free end whose
// nodes no other spring at the middle shares (their corrections would be coupled). The rest stay at
// q_n and the stability limit keeps them.
void mark_springs_at_middle(const NumericsSpec& num, Model& m) {
  std::vector<int> count(m.n_dof, 0);
  m.takes_supports_at_middle = num.supports == SpringStep::kImplicit;
  m.takes_links_at_middle = num.droppers == SpringStep::kImplicit;
  if (m.takes_supports_at_middle) {
    for (const SupportSpring& sp : m.springs) ++count[sp.dof];
    m.support_at_middle.assign(m.springs.size(), 0);
    for (std::size_t k = 0; k < m.springs.size(); ++k)
      m.support_at_middle[k] = m.inv_mass[m.springs[k].dof] > 0.0 && count[m.springs[k].dof] == 1;
  }
  if (!m.takes_links_at_middle) return;  // (refused on a 3-D line: validate_scene.cpp)
  std::vector<std::uint8_t> held(m.n_dof, 0);  // a node whose update another middle correction redoes
  for (std::size_t k = 0; k < m.support_at_middle.size(); ++k)
    if (m.support_at_middle[k]) held[m.springs[k].dof] = 1;
  auto take = [&](int a, int c) {
    if (held[a] || held[c] || !(m.inv_mass[a] > 0.0 || m.inv_mass[c] > 0.0)) return false;
    held[a] = held[c] = 1;
    return true;
  };
  m.dropper_at_middle.assign(m.droppers.size(), 0);
  for (std::size_t k = 0; k < m.droppers.size(); ++k) m.dropper_at_middle[k] = take(m.droppers[k].messenger_dof, m.droppers[k].contact_dof);
  m.clamp_at_middle.assign(m.clamps.size(), 0);
  for (std::size_t k = 0; k < m.clamps.size(); ++k) m.clamp_at_middle[k] = take(m.clamps[k].upper_dof, m.clamps[k].lower_dof);
}

// The explicit stability limit (validation.md section 5; `coupled_omega`, where given, for the
// wires' band: lean_coupled_omega_max) and the step, or the implicit matrix. Returns the wires'
// highest frequency (compute_stability_limit's), 0 for the implicit integrator.
double choose_time_step(const Scene& scene, double coupled_omega, Model& m) {
  if (scene.numerics.windowed() &&
      (scene.numerics.integrator != Integrator::kExplicit || scene.numerics.rotary_inertia != RotaryInertia::kCondensed)) {
    const bool implicit = scene.numerics.integrator != Integrator::kExplicit;
    throw SceneError(std::string("scene field ") +
                     (implicit ? "'numerics.integrator' = 'implicit': allowed 'explicit'"
                               : "'numerics.rotary_inertia' = 'lumped': allowed 'condensed'") +
                     (scene.endless ? " on an endless line (line.endless), which runs in the moving window"
                                    : " with numerics.window") +
                     " (the window integrates node ranges of the condensed band)");
  }
  if (scene.numerics.damping == DampingStep::kCentred) {
    // The centred step solves each wire's band (or its window's part) with the rotations
    // condensed, for u + beta v.
    std::string why;
    if (scene.numerics.integrator != Integrator::kExplicit) why = "numerics.integrator explicit";
    else if (scene.numerics.rotary_inertia != RotaryInertia::kCondensed) why = "numerics.rotary_inertia condensed";
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
    return 0.0;
  }
  mark_springs_at_middle(scene.numerics, m);
  const double wires = compute_stability_limit(m, coupled_omega);
  if (scene.numerics.dt) {
    if (*scene.numerics.dt > m.dt_critical)
      throw SceneError("numerics.dt = " + fmt(*scene.numerics.dt) + " s: above the explicit stability limit " +
                       fmt(m.dt_critical) + " s of this model (omega_max " + fmt(m.omega_max) +
                       " rad/s); use dt <= " + fmt(m.dt_critical) + " or dt: auto");
    m.dt = *scene.numerics.dt;
  } else {
    m.dt = scene.numerics.safety_factor * m.dt_critical;
  }
  return wires;
}

Model build_model_unchecked(const Scene& scene_in, const BuildOptions& options) {
  Scene scene = scene_in;
  if (scene.sections.empty()) add_single_section(scene);
  validate(scene);  // as given (an endless line's block and stations are made below)
  Model m;
  double endless_front = 0.0;  // train front at the start, station along the endless line
  if (scene.endless) endless_front = lay_endless_block(scene, m);
  check_model_memory(scene);
  m.scene = scene;
  m.line_length = scene.line_length();
  m.alpha = scene.rayleigh_alpha;
  m.beta = scene.rayleigh_beta;
  m.contact_stiffness = scene.contact.stiffness;
  m.rub_length = scene.contact.rub_length;
  m.support_x.assign(1, scene.sections.front().start);
  for (double l : scene.spans) m.support_x.push_back(m.support_x.back() + l);
  std::vector<double> rise_first, rise_last;
  support_rises(scene, options, rise_first, rise_last);
  int dof = 0;
  std::vector<std::vector<double>> section_supports(scene.sections.size());
  mesh_wires(scene, rise_first, rise_last, m, dof, section_supports);
  m.n_catenary_dof = dof;
  add_pantographs(scene, m, dof);
  m.n_dof = dof;
  const std::vector<bool> fixed = lump_masses(scene, m);
  hang_droppers(scene, section_supports, m);
  clamp_short_wires(scene, m);
  design_statics(scene, section_supports, m);
  apply_wear(scene, m);
  set_constant_load(scene, m, fixed);
  apply_imperfections(scene, m, fixed);
  set_pantograph_masses(m);
  set_inverse_mass(m, fixed);
  set_line_order(scene, m);
  set_train_travel(scene, endless_front, m);
  // Initial pantograph references (eq. 23); the stability limit and the step: build_model_checked.
  set_pantograph_references(m);
  if (!options.stability) m.dt = m.dt_critical = scene.numerics.dt ? *scene.numerics.dt : 1e-4;
  return m;
}


// What follows from the model's dt: the wire packs with the centred step's factors, the filter's
// cutoff checked against it, and the lateral plane timed from its design (designed here once, on
// the first call: `design`).
void time_numerics(const Scene& scene, Model& m, std::shared_ptr<const LateralModel>& design) {
  // Built here, filled further for the centred damping step below, then only read.
  const std::shared_ptr<WirePacks> packs = build_wire_packs(m);
  m.wire_packs = packs;
  if (scene.numerics.damping == DampingStep::kCentred) {
    if (!packs)  // (condensed rotations on every wire node give packs)
      throw SceneError("numerics.damping = 'centred': needs the wires' rotations condensed; allowed otherwise: half_step");
    if (scene.numerics.dt && *scene.numerics.dt > kCentredMaxSafetyFactor * m.dt_critical)
      throw SceneError("numerics.dt = " + fmt(*scene.numerics.dt) + " s: with numerics.damping centred at most " +
                       fmt(kCentredMaxSafetyFactor) + " of the stability estimate " + fmt(m.dt_critical) + " s, dt <= " +
                       fmt(kCentredMaxSafetyFactor * m.dt_critical) + " (the estimate is not a bound for that step; see numerics.safety_factor)");
    factor_centred_damping(m, *packs);
  }
  // The statistics filter runs at the step rate: a cutoff at or above its Nyquist frequency would
  // be no filter at all (lowpass_zero_phase returns the input unchanged).
  const double nyquist = 0.5 / m.dt;
  if (!(scene.output.filter_cutoff < nyquist))
    throw SceneError("scene field 'output.filter_cutoff' = " + fmt(scene.output.filter_cutoff) + ": allowed below " +
                     fmt(nyquist) + " Hz, the Nyquist frequency of the time step (dt " + fmt(m.dt) + " s)");
  if (!scene.lateral()) return;  // the 3-D line; nothing built for a 2-D scene
  if (!design) design = design_lateral(m);
  m.lateral = build_lateral(m, *design);
}

// The model with the checks that need it built: the centred step's factors, the filter's cutoff.
Model build_model_checked(const Scene& scene, const BuildOptions& options) {
  Model m = build_model_unchecked(scene, options);
  if (!options.stability) {
    m.wire_packs = build_wire_packs(m);
    return m;
  }
  const double wires = choose_time_step(m.scene, 0.0, m);
  std::shared_ptr<const LateralModel> design;
  time_numerics(scene, m, design);
  // The droppers' lean couples the planes (a mode neither plane's estimate holds): where it is
  // the highest, the model's dt again with its limit, and what follows from dt (the line and its
  // statics in both planes do not depend on it).
  // (Where a plane's own mode is the highest both iterations find it, to about 1e-9: the same
  // frequency, not a coupled one above it. Droppers hanging plumb couple nothing.)
  const auto leans = [](const LateralPendulum& p) { return p.lean0_sq > 0.0; };
  if (m.lateral && !m.implicit && std::any_of(m.lateral->pendulums.begin(), m.lateral->pendulums.end(), leans)) {
    const double coupled = lean_coupled_omega_max(m, *m.lateral);
    if (coupled > (1.0 + 1e-6) * wires) {
      choose_time_step(m.scene, coupled, m);
      time_numerics(scene, m, design);
    }
  }
  return m;
}

}  // namespace

Model build_model(const Scene& scene, const BuildOptions& options) {
  try {
    return build_model_checked(scene, options);
  } catch (const SceneError& e) {
    // A refusal found in building (the design statics, the stability limit) names the scene's
    // file as one found in reading it does; once (a section's statics build a model of their own).
    const std::string named = scene.file + ": ";
    if (scene.file.empty() || std::string(e.what()).rfind(named, 0) == 0) throw;
    throw SceneError(named + e.what());
  }
}

Model build_model(const Scene& scene) { return build_model(scene, BuildOptions{}); }

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

std::string short_element_note(const Model& m) {
  const double asked = m.scene.numerics.element_length;
  double shortest = asked;
  const Wire* on = nullptr;
  double at = 0.0;
  for (const Wire& w : m.wires)
    for (std::size_t i = 0; i + 1 < w.x.size(); ++i)
      if (w.x[i + 1] - w.x[i] < shortest) {
        shortest = w.x[i + 1] - w.x[i];
        on = &w;
        at = w.x[i];
      }
  if (!on || !(shortest < 0.5 * asked)) return "";
  std::ostringstream s;
  s.precision(3);
  s << "the mesh's shortest element is " << shortest << " m (of numerics.element_length " << asked << " m), on "
    << on->name << " at station " << at << " m, where two of its stations nearly meet (a clamp, a dropper, a support)";
  return s.str();
}

std::string speed_warning(const Model& m, double speed) {
  if (!(speed > 0.7 * m.wave_speed)) return "";
  std::ostringstream s;
  s.precision(3);
  s << "train speed " << speed * 3.6 << " km/h is " << speed / m.wave_speed << " of the contact wire's wave speed c = "
    << m.wave_speed * 3.6 << " km/h: above 0.7 c is outside design practice (the wave ahead of the pantograph steepens "
    << "and contact is lost as the speed nears c)";
  return s.str();
}

}  // namespace catenary_sim
