// The rviz drawing of a pass (to_markers) and the contact-force strip chart (to_strip_chart).
#include "catenary_sim/ros/markers.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "catenary_sim/core/simulation.hpp"
#include "line_points.hpp"

namespace catenary_sim {
namespace ros_layer {

namespace {

std_msgs::ColorRGBA color(float r, float g, float b, float a = 1.0f) {
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

geometry_msgs::Point point(double x, double y, double z) {
  geometry_msgs::Point p;
  p.x = x;
  p.y = y;
  p.z = z;
  return p;
}

visualization_msgs::Marker marker(const std_msgs::Header& h, const std::string& ns, int id, int type) {
  visualization_msgs::Marker mk;
  mk.header = h;
  mk.ns = ns;
  mk.id = id;
  mk.type = type;
  mk.action = visualization_msgs::Marker::ADD;
  mk.pose.orientation.w = 1.0;
  mk.scale.x = mk.scale.y = mk.scale.z = 1.0;
  mk.color = color(1, 1, 1);
  return mk;
}

// Lateral position of the wire node behind a vertical DOF (a dropper's or steady arm's end).
double dof_lateral(const Model& m, const State& s, int dof) {
  const int wi = wire_holding(m, dof);
  return wi < 0 ? 0.0 : node_lateral(m, s, wi, dof - m.wires[wi].w_dof);
}

// Under each collector of pantograph p, the contact wire with the lowest design height there (the
// one the head meets first, as in set_pantograph_references): its design height and its displaced
// height (weighted over the contact nodes, eq. 12), averaged over the collectors under a wire.
// Returns false (outputs untouched) when no collector is under a contact wire.
// head >= 0: only the strips of that head of Pantograph::heads.
bool lowest_contact_wire(const Model& m, const State& s, int p, double* design, double* displaced, int head = -1) {
  std::vector<int> node(m.max_contact_nodes);
  std::vector<double> weight(m.max_contact_nodes);
  double sum_design = 0.0, sum_displaced = 0.0;
  int count = 0;
  for (int ci : m.pantographs[p].collectors) {
    if (head >= 0 && m.collectors[ci].head != head) continue;
    const double xc = collector_x(m, s, p, ci);
    int k = -1;
    const double best = lowest_design_height(m, xc, &k);
    if (!std::isfinite(best)) continue;
    const int wi = m.contact_wires[k];
    const int cnt = contact_weights(m.wires[wi], m.rub_length, xc, node.data(), weight.data());
    double u = 0.0;
    for (int a = 0; a < cnt; ++a) u += weight[a] * s.wire_uplift(m, wi, node[a]);
    sum_design += best;
    sum_displaced += best + u;
    ++count;
  }
  if (count == 0) return false;
  *design = sum_design / count;
  *displaced = sum_displaced / count;
  return true;
}

// Whether any collector of pantograph p is over contact wire `wi` (an index into Model::wires).
bool under_wire(const Model& m, const State& s, int p, int wi) {
  std::vector<int> node(m.max_contact_nodes);
  std::vector<double> weight(m.max_contact_nodes);
  for (int ci : m.pantographs[p].collectors)
    if (contact_weights(m.wires[wi], m.rub_length, collector_x(m, s, p, ci), node.data(), weight.data()) > 0)
      return true;
  return false;
}

constexpr double kArrowMetresPerNewton = 0.01;  // contact-force arrow: 1 m per 100 N
constexpr double kLabelTextSize = 0.5;           // m, height of a capital letter
constexpr double kLabelLineHeight = 0.6;         // m per line of text at that size (rviz's spacing)
constexpr double kLabelClearance = 2.0;          // m between the drawn head and the label's last line
                                                 // (clear of the arrow up to 200 N)

}  // namespace

// Contact wire name as the label shows it: "contact_wire..." shortened to "cw..." so that the
// forces of two wires fit on one line ("cw_s0 47 / cw_s1 62 N").
std::string label_wire_name(const std::string& name) {
  static const std::string prefix = "contact_wire";
  return name.compare(0, prefix.size(), prefix) == 0 ? "cw" + name.substr(prefix.size()) : name;
}


double wire_dof_design_height(const Model& m, int dof) {
  const int wi = wire_holding(m, dof);
  return wi < 0 ? std::nan("") : m.wires[wi].height[dof - m.wires[wi].w_dof];
}

double contact_design_height(const Model& m, const State& s, int p) {
  double design = m.scene.contact_wire_height, displaced = 0.0;
  lowest_contact_wire(m, s, p, &design, &displaced);
  return design;
}

double drawn_head_height(const Model& m, const State& s, int p, double k) {
  double d = m.scene.contact_wire_height, y = d;
  lowest_contact_wire(m, s, p, &d, &y);
  const double head = m.pantographs[p].moving_force ? y : head_height(m, s, p);
  return d + k * (head - d);
}

double drawn_head_height(const Model& m, const State& s, int p, int head, double k) {
  const Pantograph& pg = m.pantographs[p];
  if (pg.heads.empty()) return drawn_head_height(m, s, p, k);
  // Each head about the design height of the wire over its own strips (two heads on a transition
  // span can be under different wires).
  double d = m.scene.contact_wire_height, y = d;
  if (!lowest_contact_wire(m, s, p, &d, &y, head)) lowest_contact_wire(m, s, p, &d, &y);
  return d + k * (head_height(m, s, p, head) - d);
}

namespace {
// rviz marks a whole display as Error for a list marker (LINE_LIST, LINE_STRIP, POINTS, ...) sent
// with no points ("Points should not be empty"). An empty one is sent as DELETE of its id instead,
// which also clears what it drew before (no slack dropper now, no steady arm in the scene).
void add_list(visualization_msgs::MarkerArray& out, visualization_msgs::Marker mk) {
  if (mk.points.empty()) {
    mk.action = visualization_msgs::Marker::DELETE;
    mk.colors.clear();
  }
  out.markers.push_back(mk);
}

using visualization_msgs::Marker;

// What every part of the drawing reads: the pass, the header and the vertical exaggeration k
// (wires and heads are drawn at design + k u, so that millimetres of uplift show).
struct Drawing {
  const Model& m;
  const State& s;
  const MarkerOptions& o;
  std_msgs::Header h;
  double k;
  // A wire DOF (a dropper's or steady arm's end) at its design height plus k times its uplift.
  double shown(int dof) const { return wire_dof_design_height(m, dof) + k * s.u[dof]; }
};

// A support spring of a rigid overhead conductor rail's section (its wire is the profile).
bool on_rail(const Model& m, const SupportSpring& sp) {
  return m.scene.sections[m.wires[wire_holding(m, sp.dof)].section].rigid;
}

// A support station of a catenary section (a mast there), not only of a rail's.
bool catenary_support(const Model& m, double x) {
  for (const SectionSpec& sec : m.scene.sections)
    if (!sec.rigid && x >= sec.start - 1e-6 && x <= sec.end() + 1e-6) return true;
  return false;
}

void add_wires(visualization_msgs::MarkerArray& out, const Drawing& d) {
  const Model& m = d.m;
  const State& s = d.s;
  for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
    const Wire& w = m.wires[wi];
    const bool profile = m.scene.sections[w.section].rigid;  // the aluminium profile with its wire
    Marker mk = marker(d.h, "wires", static_cast<int>(wi), Marker::LINE_STRIP);
    mk.scale.x = profile ? 0.11 : w.is_contact_wire ? 0.04 : w.is_clamped_wire ? 0.025 : 0.03;  // a profile about 110 mm high
    mk.color = profile              ? color(0.78f, 0.8f, 0.84f)
               : w.is_contact_wire ? color(0.85f, 0.55f, 0.2f)
               : w.is_clamped_wire ? color(0.65f, 0.5f, 0.3f)  // bronze
               : w.is_auxiliary_messenger ? color(0.75f, 0.45f, 0.25f)  // hard-drawn copper
                                   : color(0.6f, 0.6f, 0.65f);
    for (int i : sample_nodes(w, d.o.shape_resolution))
      mk.points.push_back(point(w.x[i] + s.line_offset, node_lateral(m, s, wi, i),
                                w.height[i] + d.k * s.wire_uplift(m, static_cast<int>(wi), i)));
    add_list(out, mk);
  }
}

// Droppers: taut grey, slack red.
void add_droppers(visualization_msgs::MarkerArray& out, const Drawing& d) {
  const State& s = d.s;
  Marker taut = marker(d.h, "droppers", 0, Marker::LINE_LIST);
  Marker slack = marker(d.h, "droppers", 1, Marker::LINE_LIST);
  taut.scale.x = slack.scale.x = 0.015;
  taut.color = color(0.7f, 0.7f, 0.7f);
  slack.color = color(1.0f, 0.1f, 0.1f);
  for (std::size_t i = 0; i < d.m.droppers.size(); ++i) {
    const Dropper& dr = d.m.droppers[i];
    Marker& mk = (i < s.dropper_slack.size() && s.dropper_slack[i]) ? slack : taut;
    mk.points.push_back(point(dr.x + s.line_offset, dof_lateral(d.m, s, dr.contact_dof), d.shown(dr.contact_dof)));
    mk.points.push_back(point(dr.x + s.line_offset, dof_lateral(d.m, s, dr.messenger_dof), d.shown(dr.messenger_dof)));
  }
  add_list(out, taut);
  add_list(out, slack);
}

// A rigid rail's supports: a drop bracket from the tunnel roof above the track to the profile.
void add_rail_supports(visualization_msgs::MarkerArray& out, const Drawing& d) {
  const Model& m = d.m;
  const State& s = d.s;
  const double roof = m.scene.contact_wire_height + 0.6;  // m, drawn only
  Marker brackets = marker(d.h, "steady_arms", 1, Marker::LINE_LIST);  // (id 0: the catenary's arms)
  brackets.scale.x = 0.08;
  brackets.color = color(0.35f, 0.35f, 0.4f);
  for (const SupportSpring& sp : m.springs) {
    if (!on_rail(m, sp)) continue;
    const double x = sp.x + s.line_offset, y = dof_lateral(m, s, sp.dof);
    brackets.points.push_back(point(x, y, roof));
    brackets.points.push_back(point(x, y, d.shown(sp.dof)));
  }
  add_list(out, brackets);
}

// Masts 3 m beside the track with a cantilever over the wires; steady arms to the contact wire.
void add_supports(visualization_msgs::MarkerArray& out, const Drawing& d) {
  const Model& m = d.m;
  const State& s = d.s;
  const auto& sections = m.scene.sections;
  if (std::any_of(sections.begin(), sections.end(), [](const SectionSpec& sec) { return sec.rigid; }))
    add_rail_supports(out, d);
  if (std::all_of(sections.begin(), sections.end(), [](const SectionSpec& sec) { return sec.rigid; })) return;
  const double y_mast = 3.0;
  const double top = m.scene.contact_wire_height + m.scene.encumbrance + 0.5;
  Marker masts = marker(d.h, "masts", 0, Marker::LINE_LIST);
  masts.scale.x = 0.15;
  masts.color = color(0.35f, 0.35f, 0.4f);
  // On a 3-D line the cantilever reaches over the messenger's stagger at that support.
  std::vector<double> reach(m.support_x.size(), 0.0);
  if (m.lateral)
    for (const LateralSupport& ls : m.lateral->supports)
      if (!m.wires[ls.wire].is_contact_wire) reach[ls.line_support] = ls.stagger;
  for (std::size_t k = 0; k < m.support_x.size(); ++k) {
    if (!catenary_support(m, m.support_x[k])) continue;
    const double x = m.support_x[k] + s.line_offset;
    masts.points.push_back(point(x, y_mast, 0.0));
    masts.points.push_back(point(x, y_mast, top));
    masts.points.push_back(point(x, y_mast, top));
    masts.points.push_back(point(x, std::min(0.0, reach[k]), top));
  }
  add_list(out, masts);
  Marker arms = marker(d.h, "steady_arms", 0, Marker::LINE_LIST);
  arms.scale.x = 0.03;
  arms.color = color(0.2f, 0.5f, 0.9f);
  for (const SupportSpring& sp : m.springs) {
    if (!sp.steady_arm || on_rail(m, sp)) continue;
    const double x = sp.x + s.line_offset, z = d.shown(sp.dof), z0 = wire_dof_design_height(m, sp.dof);
    const double y = dof_lateral(m, s, sp.dof);
    if (sp.hinged_arm()) {
      // A hinged arm as built: the registration tube from the mast to the hinge, which stands
      // a cos(theta0) against the wire's pull (on a 2-D line toward the mast) and a sin(theta0)
      // above the wire as built; the arm from the hinge to the clamp on the wire (on a 3-D line
      // the clamp has moved out with the arm's end, the hinge has not).
      const double away = sp.arm_pull_side != 0.0 ? -sp.arm_pull_side : 1.0;
      const double out = sp.arm_pull_side != 0.0 && m.lateral ? sp.arm_end_travel(s.u[sp.dof]) : 0.0;
      const double yh = y + away * (sp.arm_length * std::cos(sp.arm_inclination) + out);
      const double zh = z0 + sp.arm_length * std::sin(sp.arm_inclination);
      arms.points.push_back(point(x, y_mast, zh));
      arms.points.push_back(point(x, yh, zh));
      arms.points.push_back(point(x, yh, zh));
      arms.points.push_back(point(x, y, z));
      continue;
    }
    arms.points.push_back(point(x, y_mast, z0));
    arms.points.push_back(point(x, y, z));
  }
  add_list(out, arms);
}

// Lateral position of collector ci's contact point on its strip; NaN where it has none.
double collector_lateral(const State& s, int ci) {
  return static_cast<std::size_t>(ci) < s.lateral.collector_lateral.size() ? s.lateral.collector_lateral[ci]
                                                                           : std::nan("");
}

// One pantograph as drawn: where, how high, with what force. The head is exaggerated about the
// design height of the contact wire under it, like the wires about theirs, so it is drawn on the
// wire it touches (see drawn_head_height).
struct PantographView {
  int id = 0;
  double x = 0.0, z_head = 0.0, force = 0.0;
  bool contact = false;
  double yh = 0.0;       // across the track: the head's centre (sway)
  double y_force = 0.0;  // where the force is drawn: the mean contact point across the strips (3-D line)
  // A plain moving force is a point; a pantograph (lumped, or a real one on a rig) has one or
  // more heads, several of them each on its own suspension.
  bool point_force = false, several = false;
  int heads = 1;
  double half_width = 0.0, horn = 0.0;  // the strips' half working width, the horns' reach beyond it
};

PantographView pantograph_view(const Drawing& d, std::size_t p) {
  const Model& m = d.m;
  const State& s = d.s;
  const Pantograph& pg = m.pantographs[p];
  PantographView v;
  v.id = static_cast<int>(p);
  v.x = pantograph_position(m, s, v.id);
  v.z_head = drawn_head_height(m, s, v.id, d.k);
  v.force = total_contact_force(m, s, v.id);
  v.contact = v.force > 0.0;
  v.yh = head_lateral(m, s, p);
  v.y_force = v.yh;
  if (m.lateral) {
    double sum = 0.0;
    int count = 0;
    for (int ci : pg.collectors) {
      const double yc = collector_lateral(s, ci);
      if (std::isfinite(yc)) {
        sum += yc;
        ++count;
      }
    }
    if (count) v.y_force = v.yh + sum / count;
  }
  v.point_force = pg.moving_force && !pg.external;
  v.heads = std::max(1, head_count(m, v.id));
  v.several = !pg.heads.empty();
  v.half_width = 0.5 * m.scene.pantograph_head.working_width;
  v.horn = std::max(0.05, 0.5 * (m.scene.pantograph_head.horn_width - m.scene.pantograph_head.working_width));
  return v;
}

// The body of head hd at (xh, zh): a sphere for a moving force, a plate under the strips of one
// of several heads, else a bar across the track; red when it carries no force.
Marker head_body(const Drawing& d, std::size_t p, const PantographView& v, int hd, double xh, double zh, bool head_contact) {
  Marker head = marker(d.h, "pantograph_head", hd == 0 ? v.id : kHeadIdStride * hd + v.id,
                       v.point_force ? Marker::SPHERE : Marker::CUBE);
  if (v.point_force) {
    head.pose.position = point(v.x, v.y_force, v.z_head - 0.03);
    head.scale.x = head.scale.y = head.scale.z = 0.2;
  } else if (v.several) {
    // A plate under the head's strips, as long as the head (scene `length`).
    head.pose.position = point(xh, v.yh, zh - 0.045);
    head.scale.x = d.m.scene.pantographs[p].heads[hd].length;
    head.scale.y = 2.0 * v.half_width;
    head.scale.z = 0.03;
  } else {
    // Its top at the drawn head height (the strips' running surface), where the arrow starts.
    head.pose.position = point(v.x, v.yh, v.z_head - 0.02);
    head.scale.x = 0.1;
    head.scale.y = 2.0 * v.half_width;
    head.scale.z = 0.04;
  }
  head.color = head_contact ? color(0.25f, 0.25f, 0.28f) : color(1.0f, 0.1f, 0.1f);
  return head;
}

// The heads: collector strips across the track (carbon, pantograph_head.working_width) on each,
// and horns curving down at both ends to pantograph_head.horn_width. Several heads (each on its
// own suspension) are drawn each at its own height, centred on its own strips, with a suspension
// link down to the frame; head 0 keeps id p, head h > 0 has id kHeadIdStride h + p.
void add_heads(visualization_msgs::MarkerArray& out, const Drawing& d, std::size_t p, const PantographView& v) {
  const Model& m = d.m;
  const Pantograph& pg = m.pantographs[p];
  // Each strip a segment across the track over its own working width (strips of one head may
  // differ: collectors[].working_width), drawn as thick as a strip is wide along the track.
  Marker strips = marker(d.h, "pantograph_strips", v.id, Marker::LINE_LIST);
  strips.scale.x = 0.035;
  strips.color = v.contact ? color(0.05f, 0.05f, 0.05f) : color(1.0f, 0.1f, 0.1f);
  Marker horns = marker(d.h, "pantograph_horns", v.id, Marker::LINE_LIST);
  horns.scale.x = 0.03;
  horns.color = color(0.3f, 0.3f, 0.32f);
  Marker links = marker(d.h, "pantograph_suspension", v.id, Marker::LINE_LIST);
  links.scale.x = 0.03;
  links.color = color(0.55f, 0.55f, 0.6f);
  const double yh = v.yh, half_width = v.half_width;
  for (int hd = 0; hd < v.heads; ++hd) {
    const double zh = v.several ? drawn_head_height(m, d.s, v.id, hd, d.k) : v.z_head;
    const double xh = v.several ? v.x + m.scene.pantographs[p].heads[hd].offset : v.x;
    const bool head_contact = v.several ? d.s.head_contact_force(m, v.id, hd) > 0.0 : v.contact;
    out.markers.push_back(head_body(d, p, v, hd, xh, zh, head_contact));
    if (v.point_force) continue;
    for (int ci : pg.collectors)
      if (!v.several || m.collectors[ci].head == hd) {
        const double hw = m.collectors[ci].half_working_width;
        strips.points.push_back(point(v.x + m.collectors[ci].offset, yh - hw, zh - 0.015));
        strips.points.push_back(point(v.x + m.collectors[ci].offset, yh + hw, zh - 0.015));
      }
    for (double side : {-1.0, 1.0}) {  // from the strip's end out and down: a quarter arc in 4 pieces
      double py = yh + side * half_width, pz = zh - 0.03;
      for (int i = 1; i <= 4; ++i) {
        const double a = 0.5 * M_PI * i / 4.0;
        const double ny = yh + side * (half_width + v.horn * std::sin(a)), nz = zh - 0.03 - 0.25 * (1.0 - std::cos(a));
        horns.points.push_back(point(xh, py, pz));
        horns.points.push_back(point(xh, ny, nz));
        py = ny;
        pz = nz;
      }
    }
    if (v.several) {  // the head's suspension, down to the top of the frame under the reference point
      links.points.push_back(point(xh, yh, zh - 0.06));
      links.points.push_back(point(v.x, yh, v.z_head - 0.2));
    }
  }
  if (v.point_force) return;
  add_list(out, strips);
  add_list(out, horns);
  if (v.several) add_list(out, links);
}

// Where each strip meets the wire on a 3-D line: yellow on the working width, red beyond it (dewired).
void add_contact_points(visualization_msgs::MarkerArray& out, const Drawing& d, std::size_t p, const PantographView& v) {
  Marker spots = marker(d.h, "lateral_contact", v.id, Marker::SPHERE_LIST);
  spots.scale.x = spots.scale.y = spots.scale.z = 0.2;
  for (int ci : d.m.pantographs[p].collectors) {
    const double yc = collector_lateral(d.s, ci);
    if (!std::isfinite(yc)) continue;
    spots.points.push_back(point(v.x + d.m.collectors[ci].offset, v.yh + yc, v.z_head));
    spots.colors.push_back(std::fabs(yc) <= v.half_width ? color(1.0f, 0.85f, 0.1f) : color(1.0f, 0.1f, 0.1f));
  }
  add_list(out, spots);
}

// The frame from the roof up to the head, and the contact-force arrow up from the head.
void add_frame_and_force(visualization_msgs::MarkerArray& out, const Drawing& d, std::size_t p, const PantographView& v) {
  Marker frame = marker(d.h, "pantograph_frame", v.id, Marker::LINE_STRIP);
  frame.scale.x = 0.05;
  frame.color = color(0.3f, 0.3f, 0.3f);
  const double z_roof = std::min(4.0, v.z_head - 1.0);
  frame.points.push_back(point(v.x - 1.2, v.yh, z_roof));
  frame.points.push_back(point(v.x + 0.6, v.yh, 0.5 * (z_roof + v.z_head)));
  frame.points.push_back(point(v.x, v.yh, d.m.pantographs[p].heads.empty() ? v.z_head - 0.06 : v.z_head - 0.2));
  add_list(out, frame);

  Marker arrow = marker(d.h, "contact_force", v.id, Marker::ARROW);
  arrow.scale.x = 0.05;  // shaft diameter
  arrow.scale.y = 0.1;   // head diameter
  arrow.scale.z = 0.1;   // head length
  arrow.color = v.contact ? color(0.1f, 0.8f, 0.2f) : color(1.0f, 0.1f, 0.1f);
  arrow.points.push_back(point(v.x, v.y_force, v.z_head));
  arrow.points.push_back(point(v.x, v.y_force, v.z_head + std::max(0.0, v.force) * kArrowMetresPerNewton + 1e-3));
  out.markers.push_back(arrow);
}

// The label over the head: name and force (LOSS without contact), the force on each contact wire
// in an overlap, the contact point across the strip on a 3-D line, the train speed.
void add_label(visualization_msgs::MarkerArray& out, const Drawing& d, std::size_t p, const PantographView& v) {
  const Model& m = d.m;
  Marker label = marker(d.h, "label", v.id, Marker::TEXT_VIEW_FACING);
  label.scale.z = kLabelTextSize;
  label.color = color(1.0f, 1.0f, 1.0f);
  std::ostringstream t;
  t << std::fixed << std::setprecision(0) << m.pantographs[p].name << ": " << v.force << " N" << (v.contact ? "" : " LOSS")
    << "\n";
  int lines = 2;
  const std::size_t nw = m.contact_wires.size();
  if (nw > 1) {
    // Force on each contact wire the collectors are under (two in an overlap), on a line of its own.
    const char* sep = "";
    for (std::size_t kw = 0; kw < nw; ++kw) {
      const int wi = m.contact_wires[kw];
      if (!under_wire(m, d.s, v.id, wi)) continue;
      t << sep << label_wire_name(m.wires[wi].name) << " " << d.s.pantograph_force_on(m, v.id, static_cast<int>(kw));
      sep = " / ";
    }
    if (*sep) {
      t << " N\n";
      ++lines;
    }
  }
  if (m.lateral && v.y_force != v.yh) {  // the contact point across the strip (mean over the collectors)
    t << "strip " << std::showpos << std::setprecision(2) << v.y_force - v.yh << std::noshowpos << " m\n";
    ++lines;
  }
  t << std::setprecision(1) << d.s.speed * 3.6 << " km/h";
  // Text is centred on its position: keep its lowest line kLabelClearance above the head.
  label.pose.position = point(v.x, 0.0, v.z_head + kLabelClearance + 0.5 * lines * kLabelLineHeight);
  label.text = t.str();
  out.markers.push_back(label);
}

// Stretch across the track: positions, points and the widths of boxes and dots.
void stretch_across(visualization_msgs::MarkerArray& out, double lateral_scale) {
  for (Marker& mk : out.markers) {
    mk.pose.position.y *= lateral_scale;
    for (geometry_msgs::Point& p : mk.points) p.y *= lateral_scale;
    if (mk.type == Marker::CUBE || mk.type == Marker::CUBE_LIST || mk.type == Marker::SPHERE_LIST) mk.scale.y *= lateral_scale;
  }
}

}  // namespace

visualization_msgs::MarkerArray to_markers(const Model& m, const State& s, const ros::Time& stamp,
                                           const MarkerOptions& o) {
  visualization_msgs::MarkerArray out;
  std_msgs::Header h;
  h.stamp = stamp;
  h.frame_id = o.frame;
  const Drawing d{m, s, o, h, o.vertical_scale};
  add_wires(out, d);
  add_droppers(out, d);
  if (o.include_static) add_supports(out, d);
  for (std::size_t p = 0; p < m.pantographs.size(); ++p) {
    const PantographView v = pantograph_view(d, p);
    add_heads(out, d, p, v);
    if (!v.point_force && m.lateral) add_contact_points(out, d, p, v);
    add_frame_and_force(out, d, p, v);
    add_label(out, d, p, v);
  }
  if (o.lateral_scale != 1.0) stretch_across(out, o.lateral_scale);
  return out;
}

visualization_msgs::MarkerArray to_strip_chart(const ChartData& d, const ros::Time& stamp, const ChartOptions& o) {
  using visualization_msgs::Marker;
  visualization_msgs::MarkerArray out;
  std_msgs::Header h;
  h.stamp = stamp;
  h.frame_id = o.frame;
  const double t1 = d.time.empty() ? 0.0 : d.time.back(), t0 = t1 - o.window;
  double fmax = o.force_max;
  for (const ChartSeries& s : d.series)
    for (double f : s.force)
      if (std::isfinite(f)) fmax = std::max(fmax, 100.0 * std::ceil(f / 100.0));
  // A point of the panel: u along the time axis (m from the left edge), z height.
  auto at = [&](double u, double z) { return point(o.origin_x + u * o.dir_x, o.origin_y + u * o.dir_y, z); };
  auto pu = [&](double t) { return o.width * (t - t0) / o.window; };
  auto pz = [&](double f) { return o.z_bottom + o.height * std::clamp(f, 0.0, fmax) / fmax; };
  auto text = [&](const char* ns, int id, double u, double z, const std::string& str, std_msgs::ColorRGBA c) {
    Marker t = marker(h, ns, id, Marker::TEXT_VIEW_FACING);
    t.scale.z = o.text;
    t.color = c;
    t.pose.position = at(u, z);
    t.text = str;
    out.markers.push_back(t);
  };
  const std_msgs::ColorRGBA light = color(0.92f, 0.92f, 0.92f);

  Marker axes = marker(h, "chart_axes", 0, Marker::LINE_LIST);
  axes.scale.x = 0.03;
  axes.color = light;
  Marker grid = marker(h, "chart_axes", 1, Marker::LINE_LIST);
  grid.scale.x = 0.015;
  grid.color = color(0.92f, 0.92f, 0.92f, 0.3f);
  auto seg = [&](Marker& m, double u0, double z0, double u1, double z1) {
    m.points.push_back(at(u0, z0));
    m.points.push_back(at(u1, z1));
  };
  seg(axes, 0.0, o.z_bottom, o.width, o.z_bottom);          // time axis
  seg(axes, 0.0, o.z_bottom, 0.0, o.z_bottom + o.height);   // force axis
  int id = 0;
  for (double f = 0.0; f <= fmax + 1e-9; f += 100.0) {
    if (f > 0.0) seg(grid, 0.0, pz(f), o.width, pz(f));
    std::ostringstream t;
    t << static_cast<int>(f) << (f + 100.0 > fmax + 1e-9 ? " N" : "");
    text("chart_ticks", id++, -0.7, pz(f), t.str(), light);
  }
  for (int k = 0; k <= static_cast<int>(o.window); ++k) {  // a tick a second, from now back
    const double u = pu(t1 - k);
    if (u >= 0.0) seg(axes, u, o.z_bottom, u, o.z_bottom - 0.15);
  }
  std::ostringstream tl;
  tl << "contact force, last " << o.window << " s (a tick a second)";
  text("chart_ticks", id++, 0.5 * o.width, o.z_bottom - 0.5, tl.str(), light);
  add_list(out, axes);
  add_list(out, grid);

  // One strip per series, colours that differ on rviz's dark background.
  static const float palette[][3] = {{0.2f, 0.9f, 0.3f}, {1.0f, 0.75f, 0.2f}, {0.4f, 0.7f, 1.0f}, {1.0f, 0.4f, 0.8f},
                                     {0.9f, 0.9f, 0.3f}, {0.6f, 1.0f, 0.9f}};
  for (std::size_t k = 0; k < d.series.size(); ++k) {
    const float* c = palette[k % 6];
    Marker strip = marker(h, "chart_series", static_cast<int>(k), Marker::LINE_STRIP);
    strip.scale.x = 0.05;
    strip.color = color(c[0], c[1], c[2]);
    const ChartSeries& s = d.series[k];
    for (std::size_t i = 0; i < d.time.size() && i < s.force.size(); ++i)
      if (d.time[i] >= t0 && std::isfinite(s.force[i])) strip.points.push_back(at(pu(d.time[i]), pz(s.force[i])));
    if (strip.points.size() == 1) strip.points.push_back(strip.points.front());  // a strip needs two
    add_list(out, strip);
    // The legend under the time axis's label, one line a series.
    text("chart_legend", static_cast<int>(k), 0.5 * o.width, o.z_bottom - 1.0 - 0.45 * static_cast<double>(k), s.name,
         strip.color);
  }
  std::ostringstream it;
  it << d.heading;
  for (const std::string& line : d.stats) it << "\n" << line;
  const double lines = 1.0 + static_cast<double>(d.stats.size());
  text("chart_info", 0, 0.5 * o.width, o.z_bottom + o.height + 0.3 + 0.6 * lines * o.text, it.str(), color(1.0f, 1.0f, 1.0f));
  return out;
}

}  // namespace ros_layer
}  // namespace catenary_sim
