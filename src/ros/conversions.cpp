#include "catenary_sim/ros/conversions.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/ros/params.hpp"  // format_given: numbers in messages as the nodes write them
#include "line_points.hpp"

namespace catenary_sim {
namespace ros_layer {

std::string speed_command_error(const Scene& scene, double v) {
  const TrainSpeedLimit limit = train_speed_limit(scene);
  if (limit.allows(v)) return "";
  return "cmd/train_speed = " + format_given(v) + " m/s rejected: allowed " + limit.text();
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
      const double f = s.collector_force(m, ci);
      c.collector_forces.push_back(f);
      c.in_contact.push_back(f > 0.0);
    }
    c.total = total_contact_force(m, s, static_cast<int>(p));
    for (int wi : m.contact_wires) c.contact_wires.push_back(m.wires[wi].name);
    for (int ci : pg.collectors)
      for (std::size_t k = 0; k < m.contact_wires.size(); ++k) c.wire_forces.push_back(s.contact_force_on(m, ci, static_cast<int>(k)));
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
        ps.displacement.push_back(s.pantograph_displacement(m, static_cast<int>(p), i));
        ps.velocity.push_back(s.pantograph_velocity(m, static_cast<int>(p), i));
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
  for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
    const Wire& w = m.wires[wi];
    WireShape ws;
    ws.header = out.header;
    ws.name = w.name;
    for (int i : sample_nodes(w, resolution)) {
      ws.stations.push_back(w.x[i] + s.line_offset);
      ws.heights.push_back(s.wire_height(m, static_cast<int>(wi), i));
      if (m.lateral) ws.lateral.push_back(node_lateral(m, s, wi, i));
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
      c.in_contact = s.collector_force(m, ci) > 0.0;
      c.on_working_width = std::fabs(c.lateral) <= m.collectors[ci].half_working_width;  // false for NaN
      out.contacts.push_back(c);
    }
  }
  return out;
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
// An override's further lines (a value written over several lines): each a comment of its own, so
// that the scene's YAML below stays one document.
constexpr const char* kSceneSetMoreLine = "# catenary_sim set+ ";
}  // namespace

std::string scene_yaml_message(const std::string& path, const std::vector<std::string>& overrides) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError("cannot read scene file '" + path + "'");
  std::ostringstream text;
  char* real = ::realpath(path.c_str(), nullptr);
  text << kScenePathLine << (real ? real : path) << "\n";
  std::free(real);
  for (const std::string& o : overrides) {
    std::istringstream lines(o);
    std::string line;
    std::getline(lines, line);
    text << kSceneSetLine << line << "\n";
    while (std::getline(lines, line)) text << kSceneSetMoreLine << line << "\n";
  }
  text << in.rdbuf();
  return text.str();
}

Scene scene_from_message(const std::string& text) {
  std::string base_dir;
  std::vector<std::string> overrides;
  std::istringstream lines(text);
  const std::string head(kScenePathLine), set(kSceneSetLine), more(kSceneSetMoreLine);
  for (std::string line; std::getline(lines, line) && line.rfind("# catenary_sim ", 0) == 0;) {
    if (line.compare(0, head.size(), head) == 0) {
      const std::string path = line.substr(head.size());
      const std::size_t slash = path.rfind('/');
      if (slash != std::string::npos) base_dir = slash == 0 ? "/" : path.substr(0, slash);
    } else if (line.compare(0, set.size(), set) == 0) {
      overrides.push_back(line.substr(set.size()));
    } else if (line.compare(0, more.size(), more) == 0 && !overrides.empty()) {
      overrides.back() += "\n" + line.substr(more.size());
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
  for (std::size_t k = 0; k < m.springs.size(); ++k) {
    const SupportSpring& sp = m.springs[k];
    if (!sp.steady_arm) continue;
    bool near = false;
    for (const Pantograph& p : m.pantographs) near = near || std::fabs(sp.x - (s.front - p.position)) <= reach;
    if (!near) continue;
    const double station = sp.x + s.line_offset;
    const double most = recorder.max_steady_arm_uplift(station);
    ls.steady_arm_station.push_back(station);
    const double uplift = s.support_uplift(m, static_cast<int>(k));
    ls.steady_arm_uplift.push_back(uplift);
    // The recorder's value (stats.json's, every step while a pantograph is within half a span);
    // before a pantograph comes that close, the uplift now.
    ls.steady_arm_max_uplift.push_back(std::isnan(most) ? uplift : most);
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

std::int64_t steps_due(double wall_elapsed, double real_time_factor, double dt, double sim_done) {
  if (!(dt > 0.0) || !(real_time_factor > 0.0) || !(wall_elapsed > 0.0)) return 0;
  const double n = std::floor((real_time_factor * wall_elapsed - sim_done) / dt + 1e-9);
  // (at most 1e15: a tiny dt would give a double beyond int64, whose conversion is undefined)
  return n > 0.0 ? static_cast<std::int64_t>(std::min(n, 1e15)) : 0;
}

}  // namespace ros_layer
}  // namespace catenary_sim
