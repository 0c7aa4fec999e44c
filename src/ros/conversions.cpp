#include "catenary_sim/ros/conversions.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>

#include "catenary_sim/core/simulation.hpp"

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

// Node indices of a wire sampled at about `resolution` m, first and last node always included.
std::vector<int> sample_nodes(const Wire& w, double resolution) {
  std::vector<int> idx;
  const int n = w.nodes();
  if (n == 0) return idx;
  idx.push_back(0);
  double last = w.x[0];
  for (int i = 1; i + 1 < n; ++i) {
    if (w.x[i] - last + 1e-9 >= resolution) {
      idx.push_back(i);
      last = w.x[i];
    }
  }
  if (n > 1) idx.push_back(n - 1);
  return idx;
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


// Lateral position (m, + left of the track centre line) of node i of wire wi now; 0 on a 2-D line.
double node_lateral(const Model& m, const State& s, std::size_t wi, int i) {
  if (!m.lateral || s.lateral.y.size() != m.lateral->n) return 0.0;
  return s.lateral.y[m.lateral->wires[wi].w_dof + i];
}

// Lateral position of the wire node behind a vertical DOF (a dropper's or steady arm's end).
double dof_lateral(const Model& m, const State& s, int dof) {
  for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
    const Wire& w = m.wires[wi];
    if (dof >= w.w_dof && dof < w.w_dof + w.nodes()) return node_lateral(m, s, wi, dof - w.w_dof);
  }
  return 0.0;
}

// The pantograph head's centre across the track (sway); 0 on a 2-D line.
double head_lateral(const Model& m, const State& s, std::size_t p) {
  return m.lateral && p < s.lateral.pantograph_lateral.size() ? s.lateral.pantograph_lateral[p] : 0.0;
}

double collector_force(const Model& m, const State& s, int ci) {
  const std::size_t nw = m.contact_wires.size();
  double f = 0.0;
  for (std::size_t k = 0; k < nw; ++k) f += s.contact_force[ci * nw + k];
  return f;
}

// Station of a collector of pantograph p now, in the model's stations (the wires' x; on an
// endless line the line's station is this plus State::line_offset).
double collector_x(const Model& m, const State& s, int p, int ci) {
  return s.front - m.pantographs[p].position + m.collectors[ci].offset;
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
    const Wire& w = m.wires[m.contact_wires[k]];
    const int cnt = contact_weights(w, m.rub_length, xc, node.data(), weight.data());
    double u = 0.0;
    for (int a = 0; a < cnt; ++a) u += weight[a] * s.u[w.w_dof + node[a]];
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


std::string speed_command_error(const Scene& scene, double v) {
  const TrainSpeedLimit limit = train_speed_limit(scene);
  if (limit.allows(v)) return "";
  char what[64];
  std::snprintf(what, sizeof what, "cmd/train_speed = %g m/s rejected: allowed ", v);
  return what + limit.text();
}

ros::Time sim_stamp(double sim_time, double offset) { return ros::Time(sim_time + offset); }

ContactForceArray to_contact_force(const Model& m, const State& s, const ros::Time& stamp, const std::string& frame) {
  ContactForceArray out;
  out.header.stamp = stamp;
  out.header.frame_id = frame;
  out.sim_time = s.time;
  for (std::size_t p = 0; p < m.pantographs.size(); ++p) {
    const Pantograph& pg = m.pantographs[p];
    ContactForce c;
    c.header = out.header;
    c.name = pg.name;
    c.position = pantograph_position(m, s, static_cast<int>(p));
    for (int ci : pg.collectors) {
      const double f = collector_force(m, s, ci);
      c.collector_forces.push_back(f);
      c.in_contact.push_back(f > 0.0);
    }
    c.total = total_contact_force(m, s, static_cast<int>(p));
    const std::size_t nw = m.contact_wires.size();
    for (int wi : m.contact_wires) c.contact_wires.push_back(m.wires[wi].name);
    for (int ci : pg.collectors)
      for (std::size_t k = 0; k < nw; ++k) c.wire_forces.push_back(s.contact_force[ci * nw + k]);
    out.pantographs.push_back(c);
  }
  return out;
}

PantographStateArray to_pantograph_state(const Model& m, const State& s, const ros::Time& stamp,
                                         const std::string& frame) {
  PantographStateArray out;
  out.header.stamp = stamp;
  out.header.frame_id = frame;
  out.step = s.steps;
  out.sim_time = s.time;
  out.train_front = s.front + s.line_offset;
  out.speed = s.speed;
  out.target_speed = s.target_speed;
  out.max_acceleration = s.max_acceleration;
  for (std::size_t p = 0; p < m.pantographs.size(); ++p) {
    const Pantograph& pg = m.pantographs[p];
    PantographState ps;
    ps.header = out.header;
    ps.name = pg.name;
    ps.position = pantograph_position(m, s, static_cast<int>(p));
    ps.speed = s.speed;
    ps.head_height = head_height(m, s, static_cast<int>(p));
    if (!pg.moving_force) {
      for (int i = 0; i < pg.dof_count(); ++i) {
        ps.displacement.push_back(s.u[pg.first_dof + i]);
        ps.velocity.push_back(s.v[pg.first_dof + i]);
      }
    }
    ps.uplift = p < s.uplift.size() ? s.uplift[p] : 0.0;
    ps.aero_uplift = frame_aero_uplift(m, s, static_cast<int>(p));
    ps.head_count = head_count(m, static_cast<int>(p));
    for (int hd = 0; hd < ps.head_count; ++hd) {
      ps.head_heights.push_back(head_height(m, s, static_cast<int>(p), hd));
      ps.head_aero_uplift.push_back(head_aero_uplift(m, s, static_cast<int>(p), hd));
    }
    ps.knee = m.scene.pantographs[p].knee_trailing ? "trailing" : "leading";
    out.pantographs.push_back(ps);
  }
  return out;
}

WireShapeArray to_wire_shape(const Model& m, const State& s, double resolution, const ros::Time& stamp,
                             const std::string& frame) {
  WireShapeArray out;
  out.header.stamp = stamp;
  out.header.frame_id = frame;
  out.sim_time = s.time;
  for (const Wire& w : m.wires) {
    WireShape ws;
    ws.header = out.header;
    ws.name = w.name;
    for (int i : sample_nodes(w, resolution)) {
      ws.stations.push_back(w.x[i] + s.line_offset);
      ws.heights.push_back(w.height[i] + s.u[w.w_dof + i]);
      if (m.lateral) ws.lateral.push_back(node_lateral(m, s, &w - m.wires.data(), i));
    }
    out.wires.push_back(ws);
  }
  return out;
}

LateralContactArray to_lateral_contact(const Model& m, const State& s, const ros::Time& stamp,
                                       const std::string& frame) {
  LateralContactArray out;
  out.header.stamp = stamp;
  out.header.frame_id = frame;
  out.sim_time = s.time;
  if (!m.lateral) return out;
  out.half_working_width = m.lateral->half_working_width;
  out.half_horn_width = m.lateral->half_horn_width;
  for (std::size_t p = 0; p < m.pantographs.size(); ++p) {
    const Pantograph& pg = m.pantographs[p];
    for (std::size_t k = 0; k < pg.collectors.size(); ++k) {
      const int ci = pg.collectors[k];
      LateralContact c;
      c.pantograph = pg.name;
      c.collector = static_cast<int>(k);
      c.station = collector_x(m, s, static_cast<int>(p), ci) + s.line_offset;
      c.pantograph_lateral = head_lateral(m, s, p);
      c.lateral = static_cast<std::size_t>(ci) < s.lateral.collector_lateral.size() ? s.lateral.collector_lateral[ci]
                                                                                  : std::nan("");
      c.wire_lateral = c.lateral + c.pantograph_lateral;
      c.in_contact = collector_force(m, s, ci) > 0.0;
      c.on_working_width = std::fabs(c.lateral) <= m.collectors[ci].half_working_width;  // false for NaN
      out.contacts.push_back(c);
    }
  }
  return out;
}

double wire_dof_design_height(const Model& m, int dof) {
  for (const Wire& w : m.wires)
    if (dof >= w.w_dof && dof < w.w_dof + w.nodes()) return w.height[dof - w.w_dof];
  return std::nan("");
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

std::string train_frame_id() { return "train"; }

std::string view_frame_id() { return "train_view"; }

geometry_msgs::TransformStamped to_view_transform(const State& s, const ros::Time& stamp,
                                                  const std::string& line_frame) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = line_frame;
  t.child_frame_id = view_frame_id();
  t.transform.translation.x = s.front + s.line_offset;
  t.transform.rotation.w = 1.0;
  return t;
}

namespace {
constexpr const char* kScenePathLine = "# catenary_sim scene: ";
constexpr const char* kSceneSetLine = "# catenary_sim set: ";
}  // namespace

std::string scene_yaml_message(const std::string& path, const std::vector<std::string>& overrides) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError("cannot read scene file '" + path + "'");
  std::ostringstream text;
  char* real = ::realpath(path.c_str(), nullptr);
  text << kScenePathLine << (real ? real : path) << "\n";
  std::free(real);
  for (const std::string& o : overrides) text << kSceneSetLine << o << "\n";
  text << in.rdbuf();
  return text.str();
}

Scene scene_from_message(const std::string& text) {
  std::string base_dir;
  std::vector<std::string> overrides;
  std::istringstream lines(text);
  const std::string head(kScenePathLine), set(kSceneSetLine);
  for (std::string line; std::getline(lines, line) && line.rfind("# catenary_sim ", 0) == 0;) {
    if (line.compare(0, head.size(), head) == 0) {
      const std::string path = line.substr(head.size());
      const std::size_t slash = path.rfind('/');
      if (slash != std::string::npos) base_dir = slash == 0 ? "/" : path.substr(0, slash);
    } else if (line.compare(0, set.size(), set) == 0) {
      overrides.push_back(line.substr(set.size()));
    }
  }
  return load_scene_string(text, overrides, base_dir);
}

LineState to_line_state(const Model& m, const State& s, const PassRecorder& recorder, const ros::Time& stamp,
                        const std::string& frame) {
  LineState ls;
  ls.header.stamp = stamp;
  ls.header.frame_id = frame;
  ls.sim_time = s.time;
  for (std::uint8_t d : s.dropper_slack) ls.slack_droppers += d;
  analysis_section(m, &ls.analysis_start, &ls.analysis_end);
  const double reach = m.longest_span;
  for (const SupportSpring& sp : m.springs) {
    if (!sp.steady_arm) continue;
    bool near = false;
    for (const Pantograph& p : m.pantographs) near = near || std::fabs(sp.x - (s.front - p.position)) <= reach;
    if (!near) continue;
    const double station = sp.x + s.line_offset;
    const double most = recorder.max_steady_arm_uplift(station);
    ls.steady_arm_station.push_back(station);
    ls.steady_arm_uplift.push_back(s.u[sp.dof]);
    // The recorder's value (stats.json's, every step while a pantograph is within half a span);
    // before a pantograph comes that close, the uplift now.
    ls.steady_arm_max_uplift.push_back(std::isnan(most) ? s.u[sp.dof] : most);
  }
  return ls;
}

std::vector<geometry_msgs::TransformStamped> to_view_transforms(const Model& m, const State& s, const ros::Time& stamp,
                                                                const std::string& line_frame, int followed) {
  std::vector<geometry_msgs::TransformStamped> out{to_view_transform(s, stamp, line_frame)};
  if (m.pantographs.size() < 2) return out;
  const geometry_msgs::TransformStamped front = out.front();
  if (followed >= 0 && followed < static_cast<int>(m.pantographs.size()))
    out.front().transform.translation.x -= m.pantographs[followed].position;
  for (const Pantograph& p : m.pantographs) {
    geometry_msgs::TransformStamped t = front;
    t.child_frame_id = view_frame_id() + "_" + p.name;
    t.transform.translation.x -= p.position;
    out.push_back(t);
  }
  return out;
}

int view_pantograph_index(const Model& m, const std::string& name, const std::string& parameter) {
  if (name.empty()) return -1;
  std::string names;
  for (std::size_t p = 0; p < m.pantographs.size(); ++p) {
    if (m.pantographs[p].name == name) return static_cast<int>(p);
    names += (p ? ", " : "") + m.pantographs[p].name;
  }
  throw std::invalid_argument("parameter " + parameter + " = '" + name + "' rejected: allowed a pantograph of the scene (" +
                              names + ") or empty (the train front)");
}

std::string head_frame_id(const Model& m, int p) { return "pantograph_" + m.pantographs[p].name; }

std::vector<geometry_msgs::TransformStamped> to_transforms(const Model& m, const State& s, const ros::Time& stamp,
                                                           const std::string& line_frame) {
  std::vector<geometry_msgs::TransformStamped> out;
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = line_frame;
  t.child_frame_id = train_frame_id();
  t.transform.translation.x = s.front + s.line_offset;
  t.transform.rotation.w = 1.0;
  out.push_back(t);
  for (std::size_t p = 0; p < m.pantographs.size(); ++p) {
    const Pantograph& pg = m.pantographs[p];
    geometry_msgs::TransformStamped h;
    h.header.stamp = stamp;
    h.header.frame_id = train_frame_id();
    h.child_frame_id = head_frame_id(m, static_cast<int>(p));
    h.transform.translation.x = -pg.position;
    h.transform.translation.z = pg.moving_force ? m.scene.contact_wire_height : head_height(m, s, static_cast<int>(p));
    h.transform.rotation.w = 1.0;
    out.push_back(h);
  }
  return out;
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
}  // namespace

visualization_msgs::MarkerArray to_markers(const Model& m, const State& s, const ros::Time& stamp,
                                           const MarkerOptions& o) {
  using visualization_msgs::Marker;
  visualization_msgs::MarkerArray out;
  std_msgs::Header h;
  h.stamp = stamp;
  h.frame_id = o.frame;
  const double k = o.vertical_scale;
  auto shown = [&](int dof) { return wire_dof_design_height(m, dof) + k * s.u[dof]; };

  // Wires.
  for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
    const Wire& w = m.wires[wi];
    Marker mk = marker(h, "wires", static_cast<int>(wi), Marker::LINE_STRIP);
    mk.scale.x = w.is_contact_wire ? 0.04 : 0.03;
    mk.color = w.is_contact_wire ? color(0.85f, 0.55f, 0.2f) : color(0.6f, 0.6f, 0.65f);
    for (int i : sample_nodes(w, o.shape_resolution))
      mk.points.push_back(point(w.x[i] + s.line_offset, node_lateral(m, s, wi, i), w.height[i] + k * s.u[w.w_dof + i]));
    add_list(out, mk);
  }

  // Droppers: taut grey, slack red.
  Marker taut = marker(h, "droppers", 0, Marker::LINE_LIST);
  Marker slack = marker(h, "droppers", 1, Marker::LINE_LIST);
  taut.scale.x = slack.scale.x = 0.015;
  taut.color = color(0.7f, 0.7f, 0.7f);
  slack.color = color(1.0f, 0.1f, 0.1f);
  for (std::size_t d = 0; d < m.droppers.size(); ++d) {
    const Dropper& dr = m.droppers[d];
    Marker& mk = (d < s.dropper_slack.size() && s.dropper_slack[d]) ? slack : taut;
    mk.points.push_back(point(dr.x + s.line_offset, dof_lateral(m, s, dr.contact_dof), shown(dr.contact_dof)));
    mk.points.push_back(point(dr.x + s.line_offset, dof_lateral(m, s, dr.messenger_dof), shown(dr.messenger_dof)));
  }
  add_list(out, taut);
  add_list(out, slack);

  if (o.include_static) {
    // Masts 3 m beside the track with a cantilever over the wires; steady arms to the contact wire.
    const double y_mast = 3.0;
    const double top = m.scene.contact_wire_height + m.scene.encumbrance + 0.5;
    Marker masts = marker(h, "masts", 0, Marker::LINE_LIST);
    masts.scale.x = 0.15;
    masts.color = color(0.35f, 0.35f, 0.4f);
    // On a 3-D line the cantilever reaches over the messenger's stagger at that support.
    std::vector<double> reach(m.support_x.size(), 0.0);
    if (m.lateral)
      for (const LateralSupport& ls : m.lateral->supports)
        if (!m.wires[ls.wire].is_contact_wire) reach[ls.line_support] = ls.stagger;
    for (std::size_t k = 0; k < m.support_x.size(); ++k) {
      const double x = m.support_x[k] + s.line_offset;
      masts.points.push_back(point(x, y_mast, 0.0));
      masts.points.push_back(point(x, y_mast, top));
      masts.points.push_back(point(x, y_mast, top));
      masts.points.push_back(point(x, std::min(0.0, reach[k]), top));
    }
    add_list(out, masts);
    Marker arms = marker(h, "steady_arms", 0, Marker::LINE_LIST);
    arms.scale.x = 0.03;
    arms.color = color(0.2f, 0.5f, 0.9f);
    for (const SupportSpring& sp : m.springs) {
      if (!sp.steady_arm) continue;
      const double z = shown(sp.dof);
      arms.points.push_back(point(sp.x + s.line_offset, y_mast, wire_dof_design_height(m, sp.dof)));
      arms.points.push_back(point(sp.x + s.line_offset, dof_lateral(m, s, sp.dof), z));
    }
    add_list(out, arms);
  }

  // Pantographs: head, frame, force arrow and label. The head is exaggerated about the design
  // height of the contact wire under it, like the wires about theirs, so it is drawn on the wire
  // it touches (see drawn_head_height).
  const std::size_t nw = m.contact_wires.size();
  for (std::size_t p = 0; p < m.pantographs.size(); ++p) {
    const Pantograph& pg = m.pantographs[p];
    const int id = static_cast<int>(p);
    const double x = pantograph_position(m, s, id);
    const double z_head = drawn_head_height(m, s, id, k);
    const double force = total_contact_force(m, s, id);
    const bool contact = force > 0.0;
    // Across the track: the head's centre (sway), its strips' working width and horn extent.
    const double yh = head_lateral(m, s, p);
    // Where the force is drawn: the mean contact point across the strips on a 3-D line.
    double y_force = yh;
    if (m.lateral) {
      double sum = 0.0;
      int count = 0;
      for (int ci : pg.collectors) {
        const double yc = static_cast<std::size_t>(ci) < s.lateral.collector_lateral.size() ? s.lateral.collector_lateral[ci]
                                                                                         : std::nan("");
        if (std::isfinite(yc)) {
          sum += yc;
          ++count;
        }
      }
      if (count) y_force = yh + sum / count;
    }

    // A plain moving force is a point; a pantograph (lumped, or a real one on a rig) has one or
    // more heads: collector strips across the track (carbon, pantograph_head.working_width) on a
    // head, and horns curving down at both ends to pantograph_head.horn_width. Several heads (each
    // on its own suspension) are drawn each at its own height, centred on its own strips, with a
    // suspension link down to the frame; head 0 keeps id p, head h > 0 has id kHeadIdStride h + p.
    const bool point_force = pg.moving_force && !pg.external;
    const int heads = std::max(1, head_count(m, id));
    const bool several = !pg.heads.empty();
    const double half_width = 0.5 * m.scene.pantograph_head.working_width;
    const double horn = std::max(0.05, 0.5 * (m.scene.pantograph_head.horn_width - m.scene.pantograph_head.working_width));
    // Each strip a segment across the track over its own working width (strips of one head may
    // differ: collectors[].working_width), drawn as thick as a strip is wide along the track.
    Marker strips = marker(h, "pantograph_strips", id, Marker::LINE_LIST);
    strips.scale.x = 0.035;
    strips.color = contact ? color(0.05f, 0.05f, 0.05f) : color(1.0f, 0.1f, 0.1f);
    Marker horns = marker(h, "pantograph_horns", id, Marker::LINE_LIST);
    horns.scale.x = 0.03;
    horns.color = color(0.3f, 0.3f, 0.32f);
    Marker links = marker(h, "pantograph_suspension", id, Marker::LINE_LIST);
    links.scale.x = 0.03;
    links.color = color(0.55f, 0.55f, 0.6f);
    for (int hd = 0; hd < heads; ++hd) {
      const double zh = several ? drawn_head_height(m, s, id, hd, k) : z_head;
      double xh = x, head_force = 0.0;
      if (several) {
        xh = x + m.scene.pantographs[p].heads[hd].offset;
        for (int ci : pg.collectors)
          if (m.collectors[ci].head == hd)
            for (std::size_t kw = 0; kw < nw; ++kw) head_force += s.contact_force[ci * nw + kw];
      }
      const bool head_contact = several ? head_force > 0.0 : contact;
      Marker head = marker(h, "pantograph_head", hd == 0 ? id : kHeadIdStride * hd + id,
                           point_force ? Marker::SPHERE : Marker::CUBE);
      if (point_force) {
        head.pose.position = point(x, y_force, z_head - 0.03);
        head.scale.x = head.scale.y = head.scale.z = 0.2;
      } else if (several) {
        // A plate under the head's strips, as long as the head (scene `length`).
        head.pose.position = point(xh, yh, zh - 0.045);
        head.scale.x = m.scene.pantographs[p].heads[hd].length;
        head.scale.y = 2.0 * half_width;
        head.scale.z = 0.03;
      } else {
        // Its top at the drawn head height (the strips' running surface), where the arrow starts.
        head.pose.position = point(x, yh, z_head - 0.02);
        head.scale.x = 0.1;
        head.scale.y = 2.0 * half_width;
        head.scale.z = 0.04;
      }
      head.color = head_contact ? color(0.25f, 0.25f, 0.28f) : color(1.0f, 0.1f, 0.1f);
      out.markers.push_back(head);
      if (point_force) continue;
      for (int ci : pg.collectors)
        if (!several || m.collectors[ci].head == hd) {
          const double hw = m.collectors[ci].half_working_width;
          strips.points.push_back(point(x + m.collectors[ci].offset, yh - hw, zh - 0.015));
          strips.points.push_back(point(x + m.collectors[ci].offset, yh + hw, zh - 0.015));
        }
      for (double side : {-1.0, 1.0}) {  // from the strip's end out and down: a quarter arc in 4 pieces
        double py = yh + side * half_width, pz = zh - 0.03;
        for (int i = 1; i <= 4; ++i) {
          const double a = 0.5 * M_PI * i / 4.0;
          const double ny = yh + side * (half_width + horn * std::sin(a)), nz = zh - 0.03 - 0.25 * (1.0 - std::cos(a));
          horns.points.push_back(point(xh, py, pz));
          horns.points.push_back(point(xh, ny, nz));
          py = ny;
          pz = nz;
        }
      }
      if (several) {  // the head's suspension, down to the top of the frame under the reference point
        links.points.push_back(point(xh, yh, zh - 0.06));
        links.points.push_back(point(x, yh, z_head - 0.2));
      }
    }
    if (!point_force) {
      add_list(out, strips);
      add_list(out, horns);
      if (several) add_list(out, links);
      if (m.lateral) {
        // Where each strip meets the wire: yellow on the working width, red beyond it (dewired).
        Marker spots = marker(h, "lateral_contact", id, Marker::SPHERE_LIST);
        spots.scale.x = spots.scale.y = spots.scale.z = 0.2;
        for (int ci : pg.collectors) {
          const double yc = static_cast<std::size_t>(ci) < s.lateral.collector_lateral.size()
                                ? s.lateral.collector_lateral[ci] : std::nan("");
          if (!std::isfinite(yc)) continue;
          spots.points.push_back(point(x + m.collectors[ci].offset, yh + yc, z_head));
          spots.colors.push_back(std::fabs(yc) <= half_width ? color(1.0f, 0.85f, 0.1f) : color(1.0f, 0.1f, 0.1f));
        }
        add_list(out, spots);
      }
    }

    Marker frame = marker(h, "pantograph_frame", id, Marker::LINE_STRIP);
    frame.scale.x = 0.05;
    frame.color = color(0.3f, 0.3f, 0.3f);
    const double z_roof = std::min(4.0, z_head - 1.0);
    frame.points.push_back(point(x - 1.2, yh, z_roof));
    frame.points.push_back(point(x + 0.6, yh, 0.5 * (z_roof + z_head)));
    frame.points.push_back(point(x, yh, pg.heads.empty() ? z_head - 0.06 : z_head - 0.2));
    add_list(out, frame);

    Marker arrow = marker(h, "contact_force", id, Marker::ARROW);
    arrow.scale.x = 0.05;  // shaft diameter
    arrow.scale.y = 0.1;   // head diameter
    arrow.scale.z = 0.1;   // head length
    arrow.color = contact ? color(0.1f, 0.8f, 0.2f) : color(1.0f, 0.1f, 0.1f);
    arrow.points.push_back(point(x, y_force, z_head));
    arrow.points.push_back(point(x, y_force, z_head + std::max(0.0, force) * kArrowMetresPerNewton + 1e-3));
    out.markers.push_back(arrow);

    Marker label = marker(h, "label", id, Marker::TEXT_VIEW_FACING);
    label.scale.z = kLabelTextSize;
    label.color = color(1.0f, 1.0f, 1.0f);
    std::ostringstream t;
    t << std::fixed << std::setprecision(0) << pg.name << ": " << force << " N" << (contact ? "" : " LOSS") << "\n";
    int lines = 2;
    if (nw > 1) {
      // Force on each contact wire the collectors are under (two in an overlap), on a line of its own.
      const char* sep = "";
      for (std::size_t kw = 0; kw < nw; ++kw) {
        const int wi = m.contact_wires[kw];
        if (!under_wire(m, s, id, wi)) continue;
        double f = 0.0;
        for (int ci : pg.collectors) f += s.contact_force[ci * nw + kw];
        t << sep << label_wire_name(m.wires[wi].name) << " " << f;
        sep = " / ";
      }
      if (*sep) {
        t << " N\n";
        ++lines;
      }
    }
    if (m.lateral && y_force != yh) {  // the contact point across the strip (mean over the collectors)
      t << "strip " << std::showpos << std::setprecision(2) << y_force - yh << std::noshowpos << " m\n";
      ++lines;
    }
    t << std::setprecision(1) << s.speed * 3.6 << " km/h";
    // Text is centred on its position: keep its lowest line kLabelClearance above the head.
    label.pose.position = point(x, 0.0, z_head + kLabelClearance + 0.5 * lines * kLabelLineHeight);
    label.text = t.str();
    out.markers.push_back(label);
  }
  if (o.lateral_scale != 1.0) {
    // Stretch across the track: positions, points and the widths of boxes and dots.
    for (Marker& mk : out.markers) {
      mk.pose.position.y *= o.lateral_scale;
      for (geometry_msgs::Point& p : mk.points) p.y *= o.lateral_scale;
      if (mk.type == Marker::CUBE || mk.type == Marker::CUBE_LIST || mk.type == Marker::SPHERE_LIST) mk.scale.y *= o.lateral_scale;
    }
  }
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

std::int64_t steps_due(double wall_elapsed, double real_time_factor, double dt, double sim_done) {
  if (!(dt > 0.0) || !(real_time_factor > 0.0) || !(wall_elapsed > 0.0)) return 0;
  const double n = std::floor((real_time_factor * wall_elapsed - sim_done) / dt + 1e-9);
  // (at most 1e15: a tiny dt would give a double beyond int64, whose conversion is undefined)
  return n > 0.0 ? static_cast<std::int64_t>(std::min(n, 1e15)) : 0;
}


}  // namespace ros_layer
}  // namespace catenary_sim
