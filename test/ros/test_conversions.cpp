// Conversions of the ROS layer (State/Model -> messages, markers, transforms), pacing arithmetic
// and parameter validation: pure functions, no master needed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/ros/conversions.hpp"
#include "catenary_sim/ros/markers.hpp"
#include "catenary_sim/ros/params.hpp"
#include "../support/scenes.hpp"

#include <ros/serialization.h>
#include <xmlrpcpp/XmlRpcValue.h>

using namespace catenary_sim;
using namespace catenary_sim::ros_layer;

namespace {

struct Fixture : ::testing::Test {
  static void SetUpTestSuite() {
    sim = new Simulation(load_scene_file(test_scenes::kReference));
    for (int i = 0; i < 2000; ++i) ASSERT_EQ(sim->step(), StepStatus::kOk);
  }
  static void TearDownTestSuite() { delete sim; }
  static Simulation* sim;
  const ros::Time stamp{1000, 500};
};
Simulation* Fixture::sim = nullptr;

}  // namespace

TEST_F(Fixture, ContactForceSumsCollectorsAndFlagsContact) {
  const Model& m = sim->model();
  const State& s = sim->state();
  const ContactForceArray msg = to_contact_force(m, s, stamp, "line");
  EXPECT_EQ(msg.header.stamp, stamp);
  // Simulated time without the stamp's offset (stamp here is 1000.5 s, the pass time 2000 dt).
  EXPECT_EQ(msg.sim_time, s.time);
  EXPECT_GT(msg.sim_time, 0.0);
  EXPECT_EQ(msg.header.frame_id, "line");
  ASSERT_EQ(msg.pantographs.size(), m.pantographs.size());
  for (std::size_t p = 0; p < msg.pantographs.size(); ++p) {
    const ContactForce& c = msg.pantographs[p];
    EXPECT_EQ(c.header.stamp, stamp);
    EXPECT_EQ(c.name, m.pantographs[p].name);
    EXPECT_DOUBLE_EQ(c.position, pantograph_position(m, s, p));
    ASSERT_EQ(c.collector_forces.size(), m.pantographs[p].collectors.size());
    ASSERT_EQ(c.in_contact.size(), c.collector_forces.size());
    double sum = 0.0;
    for (std::size_t k = 0; k < c.collector_forces.size(); ++k) {
      EXPECT_GE(c.collector_forces[k], 0.0);
      EXPECT_EQ(static_cast<bool>(c.in_contact[k]), c.collector_forces[k] > 0.0);
      sum += c.collector_forces[k];
    }
    EXPECT_NEAR(c.total, sum, 1e-9);
    EXPECT_DOUBLE_EQ(c.total, total_contact_force(m, s, p));
    EXPECT_GT(c.total, 0.0);  // the reference pass keeps contact at the start
  }
}

TEST_F(Fixture, PantographStateHasEveryMass) {
  const Model& m = sim->model();
  const State& s = sim->state();
  const PantographStateArray msg = to_pantograph_state(m, s, stamp, "line");
  EXPECT_EQ(msg.step, s.steps);
  EXPECT_DOUBLE_EQ(msg.sim_time, s.time);
  EXPECT_DOUBLE_EQ(msg.speed, s.speed);
  EXPECT_DOUBLE_EQ(msg.train_front, s.front);
  ASSERT_EQ(msg.pantographs.size(), m.pantographs.size());
  const Pantograph& pg = m.pantographs[0];
  const PantographState& ps = msg.pantographs[0];
  ASSERT_EQ(ps.displacement.size(), static_cast<std::size_t>(pg.masses_count()));
  ASSERT_EQ(ps.velocity.size(), ps.displacement.size());
  for (int i = 0; i < pg.masses_count(); ++i) {
    EXPECT_DOUBLE_EQ(ps.displacement[i], s.pantograph_displacement(m, 0, i));
    EXPECT_DOUBLE_EQ(ps.velocity[i], s.pantograph_velocity(m, 0, i));
  }
  EXPECT_DOUBLE_EQ(ps.uplift, s.uplift[0]);
  EXPECT_DOUBLE_EQ(ps.head_height, head_height(m, s, 0));
  EXPECT_DOUBLE_EQ(ps.speed, s.speed);
  // A chain is one head (its first mass), whose aero is the frame's.
  EXPECT_EQ(ps.head_count, 1);
  ASSERT_EQ(ps.head_heights.size(), 1u);
  EXPECT_DOUBLE_EQ(ps.head_heights[0], pg.reference_height + s.pantograph_displacement(m, 0, 0));
  ASSERT_EQ(ps.head_aero_uplift.size(), 1u);
  EXPECT_EQ(ps.head_aero_uplift[0], 0.0);
  EXPECT_EQ(ps.knee, "leading");
}

TEST_F(Fixture, WireShapeSamplesAtResolutionAndKeepsEnds) {
  const Model& m = sim->model();
  const State& s = sim->state();
  for (double res : {0.0, 1.0, 5.0}) {
    const WireShapeArray msg = to_wire_shape(m, s, res, stamp, "line");
    EXPECT_EQ(msg.sim_time, s.time);
    ASSERT_EQ(msg.wires.size(), m.wires.size());
    for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
      const Wire& w = m.wires[wi];
      const WireShape& ws = msg.wires[wi];
      EXPECT_EQ(ws.name, w.name);
      ASSERT_EQ(ws.stations.size(), ws.heights.size());
      if (res == 0.0) {
        EXPECT_EQ(ws.stations.size(), static_cast<std::size_t>(w.nodes()));
      }
      EXPECT_DOUBLE_EQ(ws.stations.front(), w.x.front());
      EXPECT_DOUBLE_EQ(ws.stations.back(), w.x.back());
      double max_gap = 0.0;
      for (std::size_t k = 1; k < ws.stations.size(); ++k) {
        EXPECT_GT(ws.stations[k], ws.stations[k - 1]);
        max_gap = std::max(max_gap, ws.stations[k] - ws.stations[k - 1]);
      }
      EXPECT_LE(max_gap, res + m.scene.numerics.element_length + 1e-9);
      // Heights are design + displacement at the sampled node.
      for (std::size_t k = 0; k < ws.stations.size(); k += 17) {
        int node = -1;
        for (int i = 0; i < w.nodes(); ++i)
          if (w.x[i] == ws.stations[k]) node = i;
        ASSERT_GE(node, 0);
        EXPECT_DOUBLE_EQ(ws.heights[k], s.wire_height(m, static_cast<int>(wi), node));
      }
    }
  }
}

TEST_F(Fixture, TransformsLineTrainHead) {
  const Model& m = sim->model();
  const State& s = sim->state();
  const auto tfs = to_transforms(m, s, stamp, "line");
  ASSERT_EQ(tfs.size(), 1 + m.pantographs.size());
  EXPECT_EQ(tfs[0].header.frame_id, "line");
  EXPECT_EQ(tfs[0].child_frame_id, train_frame_id());
  EXPECT_DOUBLE_EQ(tfs[0].transform.translation.x, s.front);
  EXPECT_EQ(tfs[1].header.frame_id, train_frame_id());
  EXPECT_EQ(tfs[1].child_frame_id, "pantograph_leading");
  EXPECT_DOUBLE_EQ(tfs[0].transform.translation.x + tfs[1].transform.translation.x, pantograph_position(m, s, 0));
  EXPECT_DOUBLE_EQ(tfs[1].transform.translation.z, head_height(m, s, 0));
  for (const auto& t : tfs) {
    EXPECT_EQ(t.header.stamp, stamp);
    EXPECT_DOUBLE_EQ(t.transform.rotation.w, 1.0);
  }
}

TEST_F(Fixture, MarkersCoverEveryPartAndExaggerateDisplacement) {
  const Model& m = sim->model();
  const State& s = sim->state();
  MarkerOptions o;
  o.vertical_scale = 10.0;
  o.shape_resolution = 0.0;
  const auto arr = to_markers(m, s, stamp, o);
  std::set<std::string> ns;
  for (const auto& mk : arr.markers) {
    ns.insert(mk.ns);
    EXPECT_EQ(mk.header.frame_id, "line");
    EXPECT_EQ(mk.header.stamp, stamp);
    for (const auto& p : mk.points) {
      EXPECT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) << mk.ns;
    }
  }
  for (const char* n : {"wires", "droppers", "masts", "steady_arms", "pantograph_head", "pantograph_frame",
                        "contact_force", "label"})
    EXPECT_EQ(ns.count(n), 1u) << n;
  // Contact wire strip: z = design + 10 u at every node.
  const Wire& w = m.wires[0];
  const auto& strip = arr.markers[0];
  ASSERT_EQ(strip.points.size(), static_cast<std::size_t>(w.nodes()));
  for (int i = 0; i < w.nodes(); i += 31) EXPECT_DOUBLE_EQ(strip.points[i].z, w.height[i] + 10.0 * s.wire_uplift(m, 0, i));
  // Unique (ns, id) pairs, or rviz would overwrite markers.
  std::set<std::pair<std::string, int>> ids;
  for (const auto& mk : arr.markers) EXPECT_TRUE(ids.insert({mk.ns, mk.id}).second) << mk.ns << " " << mk.id;
  EXPECT_NE(arr.markers.back().text.find("km/h"), std::string::npos);
}

// A catenary joined to a rigid rail: masts and steady arms on the catenary's supports, drop
// brackets on the rail's, each support drawn once (the joint's two shared supports carry both
// the wire's and the profile's), every marker with an (ns, id) of its own.
TEST(Markers, ACatenaryJoinedToTheRailDrawsEachKindOfSupport) {
  Simulation sim(load_scene_file(test_scenes::scene_path("catenary_to_rigid_rail.yaml")));
  const Model& m = sim.model();
  MarkerOptions o;
  const auto arr = to_markers(m, sim.state(), ros::Time(1.0), o);
  std::set<std::pair<std::string, int>> ids;
  for (const auto& mk : arr.markers) EXPECT_TRUE(ids.insert({mk.ns, mk.id}).second) << mk.ns << " " << mk.id;
  int catenary_arms = 0, rail_supports = 0;
  for (const SupportSpring& sp : m.springs) {
    if (!sp.steady_arm) continue;
    for (const Wire& w : m.wires)
      if (sp.dof >= w.w_dof && sp.dof < w.w_dof + w.nodes()) ++(m.scene.sections[w.section].rigid ? rail_supports : catenary_arms);
  }
  ASSERT_GT(catenary_arms, 0);
  ASSERT_GT(rail_supports, 0);
  const visualization_msgs::Marker* arms = nullptr;
  const visualization_msgs::Marker* brackets = nullptr;
  const visualization_msgs::Marker* masts = nullptr;
  for (const auto& mk : arr.markers) {
    if (mk.ns == "steady_arms" && mk.id == 0) arms = &mk;
    if (mk.ns == "steady_arms" && mk.id == 1) brackets = &mk;
    if (mk.ns == "masts") masts = &mk;
  }
  ASSERT_TRUE(arms && brackets && masts);
  EXPECT_EQ(arms->points.size(), 2u * catenary_arms);
  EXPECT_EQ(brackets->points.size(), 2u * rail_supports);
  // Masts (four points each) stand at the catenary's supports, 0-262 m, and not along the rail.
  const double catenary_end = m.scene.sections[0].end();
  int catenary_stations = 0;
  for (double x : m.support_x) catenary_stations += x <= catenary_end + 1e-6;
  EXPECT_EQ(masts->points.size(), 4u * catenary_stations);
  for (const auto& p : masts->points) EXPECT_LE(p.x, catenary_end + 1e-6);
}

namespace {

// Steps `sim` until its first pantograph reaches station x (m).
void step_to(Simulation& sim, double x) {
  while (pantograph_position(sim.model(), sim.state(), 0) < x) ASSERT_EQ(sim.step(), StepStatus::kOk);
}

const visualization_msgs::Marker* find_marker(const visualization_msgs::MarkerArray& a, const std::string& ns, int id) {
  for (const auto& mk : a.markers)
    if (mk.ns == ns && mk.id == id) return &mk;
  return nullptr;
}

// Height of a drawn line strip at station x (linear between its points).
double strip_z(const visualization_msgs::Marker& strip, double x) {
  const auto& pts = strip.points;
  for (std::size_t i = 1; i < pts.size(); ++i)
    if (pts[i].x >= x) {
      const double t = (x - pts[i - 1].x) / (pts[i].x - pts[i - 1].x);
      return pts[i - 1].z + t * (pts[i].z - pts[i - 1].z);
    }
  return std::nan("");
}

}  // namespace

// The head is exaggerated about the design height of the wire under it, as the wire is: at
// mid-span (presag 55 mm) with k = 10 it is drawn on the wire it touches. Exaggerating it about
// its reference height (the wire's height where the pass started, at a support) drew it
// (k - 1) x 55 mm ~ 0.5 m under the wire.
TEST(Markers, HeadIsDrawnOnTheWireItTouchesAtMidSpan) {
  Simulation sim(load_scene_file(test_scenes::kReference));
  const Model& m = sim.model();
  const double x_mid = m.support_x[1] + 0.5 * (m.support_x[2] - m.support_x[1]);
  step_to(sim, x_mid);
  const State& s = sim.state();
  const double k = 10.0;
  MarkerOptions o;
  o.vertical_scale = k;
  o.shape_resolution = 0.0;
  const auto arr = to_markers(m, s, ros::Time(1.0), o);
  const Pantograph& pg = m.pantographs[0];
  const double x = pantograph_position(m, s, 0);
  const double force = total_contact_force(m, s, 0);
  ASSERT_GT(force, 0.0);
  const int cw = m.contact_wires[0];
  const auto* wire = find_marker(arr, "wires", cw);
  const auto* head = find_marker(arr, "pantograph_head", 0);
  const auto* arrow = find_marker(arr, "contact_force", 0);
  ASSERT_TRUE(wire && head && arrow);
  const double z_wire = strip_z(*wire, x);
  const double head_top = head->pose.position.z + 0.5 * head->scale.z;
  // In contact the head is above the wire by k x the contact spring's compression (F / k0: a few mm).
  const double expected_gap = k * force / m.contact_stiffness;
  EXPECT_NEAR(head_top - z_wire, expected_gap, 0.02) << "head top " << head_top << ", wire " << z_wire;
  EXPECT_LT(std::fabs(head_top - z_wire), 0.05);
  EXPECT_NEAR(contact_design_height(m, s, 0), m.scene.contact_wire_height - 0.055, 0.005);
  EXPECT_NEAR(drawn_head_height(m, s, 0, 1.0), head_height(m, s, 0), 1e-12);  // k = 1: the true height
  // The old rule (reference height + k u) is far off here, so this test tells the two apart.
  EXPECT_GT(std::fabs(pg.reference_height + k * s.pantograph_displacement(m, 0, 0) - z_wire), 0.3);
  // The arrow starts on the head and is 1 m per 100 N.
  EXPECT_DOUBLE_EQ(arrow->points[0].z, head_top);
  EXPECT_NEAR(arrow->points[1].z - arrow->points[0].z, force / 100.0, 2e-3);
  // The label is white, 0.5 m, above the arrow's usual length.
  const auto* label = find_marker(arr, "label", 0);
  ASSERT_TRUE(label);
  EXPECT_EQ(label->color.r, 1.0f);
  EXPECT_EQ(label->color.g, 1.0f);
  EXPECT_EQ(label->color.b, 1.0f);
  EXPECT_EQ(label->color.a, 1.0f);
  EXPECT_DOUBLE_EQ(label->scale.z, 0.5);
  // One contact wire: "leading: 101 N" and the speed, no line per contact wire.
  EXPECT_EQ(std::count(label->text.begin(), label->text.end(), '\n'), 1) << label->text;
  EXPECT_EQ(label->text.rfind(pg.name + ": ", 0), 0u) << label->text;
  EXPECT_GT(label->pose.position.z, arrow->points[1].z) << "label over the arrow";
}

// A pantograph with two heads (config/reference_55m_two_heads.yaml: heads at +-0.25 m on their
// own suspensions, each with its own aero term 0.002 N s^2/m^2): the state carries both heads and
// the markers draw each at its own height on the wire over its own strip, with its own horns.
TEST(Markers, TwoHeadsEachInTheStateAndDrawnOverItsOwnStrip) {
  Simulation sim(load_scene_file(test_scenes::kReferenceTwoHeads));
  const Model& m = sim.model();
  const double x_mid = m.support_x[1] + 0.5 * (m.support_x[2] - m.support_x[1]);
  step_to(sim, x_mid);
  const State& s = sim.state();
  const Pantograph& pg = m.pantographs[0];
  ASSERT_EQ(pg.heads.size(), 2u);

  const PantographStateArray msg = to_pantograph_state(m, s, ros::Time(1.0), "line");
  const PantographState& ps = msg.pantographs[0];
  EXPECT_EQ(ps.head_count, 2);
  ASSERT_EQ(ps.head_heights.size(), 2u);
  ASSERT_EQ(ps.head_aero_uplift.size(), 2u);
  ASSERT_EQ(ps.displacement.size(), static_cast<std::size_t>(pg.masses_count() + 2));  // frame, then heads
  for (int h = 0; h < 2; ++h) {
    EXPECT_DOUBLE_EQ(ps.head_heights[h], pg.heads[h].reference_height + s.u[pg.heads[h].dof]);
    EXPECT_DOUBLE_EQ(ps.displacement[pg.masses_count() + h], s.pantograph_displacement(m, 0, pg.masses_count() + h));
    EXPECT_NEAR(ps.head_aero_uplift[h], 0.002 * s.speed * s.speed, 1e-12);  // the scene's a_h v^2
  }
  EXPECT_NEAR(ps.head_height, 0.5 * (ps.head_heights[0] + ps.head_heights[1]), 1e-12);
  EXPECT_NE(ps.head_heights[0], ps.head_heights[1]) << "each head on its own suspension";
  EXPECT_EQ(ps.knee, "leading");
  EXPECT_EQ(ps.aero_uplift, 0.0);  // the frame's

  const double k = 10.0;
  MarkerOptions o;
  o.vertical_scale = k;
  o.shape_resolution = 0.0;
  const auto arr = to_markers(m, s, ros::Time(1.0), o);
  const double x = pantograph_position(m, s, 0);
  const auto* wire = find_marker(arr, "wires", m.contact_wires[0]);
  const auto* strips = find_marker(arr, "pantograph_strips", 0);
  const auto* horns = find_marker(arr, "pantograph_horns", 0);
  const auto* links = find_marker(arr, "pantograph_suspension", 0);
  ASSERT_TRUE(wire && strips && horns && links);
  // One segment across the track per strip, over its working width.
  ASSERT_EQ(strips->points.size(), 4u);
  EXPECT_EQ(strips->type, visualization_msgs::Marker::LINE_LIST);
  EXPECT_NEAR(strips->points[1].y - strips->points[0].y, m.scene.pantograph_head.working_width, 1e-12);
  // Two heads x two sides x a quarter arc of 4 segments, 2 points each.
  EXPECT_EQ(horns->points.size(), 32u);
  EXPECT_EQ(links->points.size(), 4u);
  for (int h = 0; h < 2; ++h) {
    const double xh = x + (h == 0 ? 0.25 : -0.25);  // the scene's head offsets
    const auto* head = find_marker(arr, "pantograph_head", h == 0 ? 0 : kHeadIdStride);
    ASSERT_TRUE(head) << "head " << h;
    EXPECT_NEAR(head->pose.position.x, xh, 1e-9);
    EXPECT_NEAR(head->scale.x, 0.3, 1e-12);  // the head's length
    const auto& strip = strips->points[2 * h];  // (its segment's first end)
    EXPECT_NEAR(strip.x, xh, 1e-9);
    // Its strip's top on the wire over it, k x that strip's contact-spring compression above.
    const double f = s.head_contact_force(m, 0, h);
    ASSERT_GT(f, 0.0);
    const double top = strip.z + 0.015;  // (a strip 30 mm high, drawn along its centre line)
    EXPECT_NEAR(top - strip_z(*wire, xh), k * f / m.contact_stiffness, 0.02) << "head " << h;
    EXPECT_NEAR(top, drawn_head_height(m, s, 0, h, k), 1e-12);
    // Its horns at its own station, reaching the scene's horn width.
    double reach = 0.0;
    for (const auto& pt : horns->points)
      if (std::fabs(pt.x - xh) < 1e-9) reach = std::max(reach, std::fabs(pt.y));
    EXPECT_NEAR(reach, 0.5 * m.scene.pantograph_head.horn_width, 1e-9) << "head " << h;
  }
}

// In the overlap of calpe_example the collectors are under both contact wires: the head is drawn
// on the lower one and the label gives the force on each.
TEST(Markers, EachStripIsDrawnOverItsOwnWorkingWidth) {
  // Two strips of one head with working widths of 1.2 m and 0.5 m (collectors[].working_width):
  // each drawn across the track over its own width, centred on the head, at its own offset.
  Simulation sim(load_scene_file(test_scenes::kReference,
                                 {"stagger.contact_wire=[0.3,-0.3]", "pantographs.0.collectors=[{offset: 0.3, "
                                  "working_width: 1.2}, {offset: -0.3, working_width: 0.5}]"}));
  const Model& m = sim.model();
  const auto arr = to_markers(m, sim.state(), ros::Time(1.0), MarkerOptions());
  const auto* strips = find_marker(arr, "pantograph_strips", 0);
  ASSERT_TRUE(strips);
  ASSERT_EQ(strips->points.size(), 4u);
  const double x = pantograph_position(m, sim.state(), 0);
  const double widths[2] = {1.2, 0.5}, offsets[2] = {0.3, -0.3};
  for (int c = 0; c < 2; ++c) {
    const geometry_msgs::Point &a = strips->points[2 * c], &b = strips->points[2 * c + 1];
    EXPECT_NEAR(b.y - a.y, widths[c], 1e-12) << "strip " << c;
    EXPECT_NEAR(0.5 * (a.y + b.y), sim.state().lateral.pantograph_lateral[0], 1e-12) << "strip " << c;
    EXPECT_NEAR(a.x, x + offsets[c], 1e-9) << "strip " << c;
    EXPECT_EQ(a.x, b.x);
  }
}

TEST(Markers, OverlapLabelGivesTheForcePerContactWire) {
  Simulation sim(load_scene_file(test_scenes::kCalpeExample));
  const Model& m = sim.model();
  ASSERT_EQ(m.contact_wires.size(), 2u);
  step_to(sim, 50.0);
  const State& s = sim.state();
  MarkerOptions o;
  o.shape_resolution = 0.0;
  const auto arr = to_markers(m, s, ros::Time(1.0), o);
  const auto* label = find_marker(arr, "label", 0);
  const auto* head = find_marker(arr, "pantograph_head", 0);
  ASSERT_TRUE(label && head);
  const ContactForce c = to_contact_force(m, s, ros::Time(1.0), "line").pantographs[0];
  ASSERT_EQ(c.contact_wires.size(), 2u);
  // A line with the force on each wire, "contact_wire" shortened to "cw": "cw_s0 47 / cw_s1 62 N".
  ASSERT_EQ(c.contact_wires[0], "contact_wire_s0");
  ASSERT_EQ(c.contact_wires[1], "contact_wire_s1");
  const std::size_t nl = label->text.find('\n');
  ASSERT_NE(nl, std::string::npos) << label->text;
  const std::string line = label->text.substr(nl + 1, label->text.find('\n', nl + 1) - nl - 1);
  char expected[128];
  std::snprintf(expected, sizeof expected, "cw_s0 %.0f / cw_s1 %.0f N", c.wire_forces[0], c.wire_forces[1]);
  EXPECT_EQ(line, expected) << label->text;
  EXPECT_GT(c.wire_forces[0], 0.0);  // touching both wires at 50 m
  EXPECT_GT(c.wire_forces[1], 0.0);
  EXPECT_EQ(std::count(label->text.begin(), label->text.end(), '\n'), 2) << label->text;
  // Drawn on the lower of the two drawn contact wires, within a few cm.
  const double x = pantograph_position(m, s, 0);
  double lowest = std::numeric_limits<double>::infinity();
  for (int wi : m.contact_wires) lowest = std::min(lowest, strip_z(*find_marker(arr, "wires", wi), x));
  const double head_top = head->pose.position.z + 0.5 * head->scale.z;
  EXPECT_LT(std::fabs(head_top - lowest), 0.1) << "head top " << head_top << ", lower wire " << lowest << "; "
                                                << label->text;
}

TEST(Markers, ViewFrameFollowsTheTrainFront) {
  State s;
  s.front = 123.25;
  const auto t = to_view_transform(s, ros::Time(5.0), "line");
  EXPECT_EQ(t.header.frame_id, "line");
  EXPECT_EQ(t.child_frame_id, "train_view");
  EXPECT_EQ(view_frame_id(), "train_view");
  EXPECT_EQ(t.header.stamp, ros::Time(5.0));
  EXPECT_DOUBLE_EQ(t.transform.translation.x, 123.25);
  EXPECT_DOUBLE_EQ(t.transform.rotation.w, 1.0);
}

// With two pantographs (200 m apart in the scene) each has a view frame at its own station, so a
// camera can follow the trailing one; train_view stays at the front. One pantograph: train_view only.
TEST(Markers, EveryPantographHasAViewFrameOnATrainWithSeveral) {
  Simulation two(load_scene_file(test_scenes::kReferenceTwoPantographs));
  const Model& m = two.model();
  const State& s = two.state();
  const auto v = to_view_transforms(m, s, ros::Time(5.0), "line");
  ASSERT_EQ(v.size(), 3u);
  EXPECT_EQ(v[0].child_frame_id, "train_view");
  for (std::size_t p = 0; p < 2; ++p) {
    EXPECT_EQ(v[p + 1].child_frame_id, "train_view_" + m.pantographs[p].name);
    EXPECT_EQ(v[p + 1].header.stamp, ros::Time(5.0));
    EXPECT_DOUBLE_EQ(v[p + 1].transform.translation.x, s.front + s.line_offset - m.pantographs[p].position);
  }
  EXPECT_DOUBLE_EQ(v[1].transform.translation.x - v[2].transform.translation.x, 200.0);
  Simulation one(load_scene_file(test_scenes::kReference));
  EXPECT_EQ(to_view_transforms(one.model(), one.state(), ros::Time(5.0), "line").size(), 1u);
}

// ~view_pantograph: train_view (the default camera and the strip chart) at the station of the
// pantograph named, the per-pantograph frames unchanged; a name not in the scene is refused with
// the names allowed. (Stations are exact: a difference of the scene's positions.)
TEST(Markers, TrainViewFollowsTheChosenPantograph) {
  Simulation two(load_scene_file(std::string(CATENARY_SIM_SOURCE_DIR) + "/config/reference_55m_two_pantographs.yaml"));
  const Model& m = two.model();
  const State& s = two.state();
  const int trailing = view_pantograph_index(m, m.pantographs[1].name, "~view_pantograph");
  EXPECT_EQ(trailing, 1);
  EXPECT_EQ(view_pantograph_index(m, "", "~view_pantograph"), -1);
  const auto front = to_view_transforms(m, s, ros::Time(5.0), "line");
  const auto v = to_view_transforms(m, s, ros::Time(5.0), "line", trailing);
  ASSERT_EQ(v.size(), 3u);
  EXPECT_EQ(v[0].child_frame_id, "train_view");
  EXPECT_DOUBLE_EQ(v[0].transform.translation.x, s.front + s.line_offset - m.pantographs[1].position);
  for (std::size_t i = 1; i < 3; ++i)
    EXPECT_DOUBLE_EQ(v[i].transform.translation.x, front[i].transform.translation.x);
  try {
    view_pantograph_index(m, "middle", "~view_pantograph");
    ADD_FAILURE() << "an unknown pantograph was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("~view_pantograph = 'middle'"), std::string::npos) << what;
    EXPECT_NE(what.find(m.pantographs[0].name), std::string::npos) << what;
    EXPECT_NE(what.find(m.pantographs[1].name), std::string::npos) << what;
  }
}

TEST(Pacing, StepsDueFollowWallClockTimesFactor) {
  EXPECT_EQ(steps_due(1.0, 1.0, 1e-3, 0.0), 1000);
  EXPECT_EQ(steps_due(1.0, 2.0, 1e-3, 0.0), 2000);
  EXPECT_EQ(steps_due(1.0, 1.0, 1e-3, 0.5), 500);
  EXPECT_EQ(steps_due(1.0, 1.0, 1e-3, 2.0), 0);   // ahead: nothing due, never negative
  EXPECT_EQ(steps_due(1.0, 0.0, 1e-3, 0.0), 0);   // factor 0 is handled by the caller
  EXPECT_EQ(steps_due(0.0, 1.0, 1e-3, 0.0), 0);
  EXPECT_EQ(steps_due(0.0105, 1.0, 1e-3, 0.0), 10);  // whole steps only: dt is never stretched
}

// The pass node and the HIL node reject cmd/train_speed with this message (the same range as the
// core's set_target_speed, which stays the authority).
TEST(Commands, SpeedCommandErrorNamesTopicValueAndRange) {
  Simulation sim(load_scene_file(test_scenes::kReference));
  const Scene& scene = sim.model().scene;
  const double c = std::sqrt(22000.0 / 1.35);  // the reference contact wire's wave speed, m/s
  EXPECT_EQ(speed_command_error(scene, 0.0), "");
  EXPECT_EQ(speed_command_error(scene, 0.99 * c), "");
  EXPECT_EQ(speed_command_error(scene, 200.0).rfind("cmd/train_speed = 200 m/s rejected: allowed 0 to below ", 0), 0u);
  EXPECT_NE(speed_command_error(scene, c).find("wave speed"), std::string::npos);
  EXPECT_NE(speed_command_error(scene, -0.5).find("= -0.5 m/s rejected"), std::string::npos);
  EXPECT_NE(speed_command_error(scene, std::nan("")).find("= nan m/s rejected"), std::string::npos);
  // Just past the bound, printed whole (not as the bound it passes).
  EXPECT_NE(speed_command_error(scene, 150.0000001).find("= 150.0000001 m/s rejected"), std::string::npos);
  EXPECT_NE(speed_command_error(scene, std::numeric_limits<double>::infinity()), "");
  // Whatever it accepts the core accepts, and the other way round.
  for (double v : {-1e-9, 0.0, 75.0, 0.99 * c, c, 150.0, 150.0000001, std::nan("")})
    EXPECT_EQ(speed_command_error(scene, v).empty(), sim.set_target_speed(v, nullptr)) << v;
}

TEST(Stamps, OffsetAddsAndIsMonotonic) {
  EXPECT_EQ(sim_stamp(1.5, 100.0), ros::Time(101.5));
  EXPECT_LT(sim_stamp(1.0, 100.0), sim_stamp(1.0001, 100.0));
}

TEST(Params, ErrorsNameParameterValueAndRange) {
  NodeParams p;
  p.scene = "x.yaml";
  EXPECT_NO_THROW(validate(p));
  auto message = [](const NodeParams& q) {
    try {
      validate(q);
    } catch (const ParamError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  NodeParams q = p;
  q.publish_rate = -5.0;
  std::string e = message(q);
  EXPECT_NE(e.find("publish_rate"), std::string::npos) << e;
  EXPECT_NE(e.find("-5"), std::string::npos) << e;
  EXPECT_NE(e.find("10000"), std::string::npos) << e;
  q = p;
  q.real_time_factor = std::nan("");
  EXPECT_NE(message(q).find("real_time_factor"), std::string::npos);
  q = p;
  q.speed_kmh = 600.0;
  EXPECT_NE(message(q).find("speed_kmh = 600"), std::string::npos);
  q = p;
  q.marker_rate = 0.0;
  e = message(q);
  EXPECT_NE(e.find("marker_rate = 0"), std::string::npos) << e;
  EXPECT_NE(e.find("[0.1, 1000] Hz"), std::string::npos) << e;
  EXPECT_EQ(NodeParams().marker_rate, 30.0);
  q = p;
  q.max_acceleration = 25.0;
  EXPECT_NE(message(q).find("max_acceleration"), std::string::npos);
  q = p;
  q.scene.clear();
  EXPECT_NE(message(q).find("~scene is required"), std::string::npos);
  EXPECT_THROW(parse_at_end("rewind"), ParamError);
  EXPECT_EQ(parse_at_end("loop"), AtEnd::kLoop);
  p.scene = "/nonexistent/scene.yaml";
  try {
    load_scene(p);
    FAIL() << "no error for a missing scene file";
  } catch (const ParamError& err) {
    EXPECT_NE(std::string(err.what()).find("/nonexistent/scene.yaml"), std::string::npos);
  }
}

// The lower bounds of the rates keep every period within ros::WallDuration (int32 seconds): the
// values 1e-10 and 1e-300 are refused with the parameter named, and the smallest value allowed
// gives a period that a WallDuration holds (constructing it throws past 2^31 s).
TEST(Params, AbsurdRatesAreRejectedAndTheSmallestAllowedHasAPeriod) {
  NodeParams p;
  p.scene = "x.yaml";
  struct Rate {
    const char* name;
    double NodeParams::*field;
    double min;
  };
  for (const Rate& r : {Rate{"publish_rate", &NodeParams::publish_rate, kMinPublishRate},
                        Rate{"shape_rate", &NodeParams::shape_rate, kMinShapeRate},
                        Rate{"marker_rate", &NodeParams::marker_rate, kMinMarkerRate}}) {
    for (double bad : {1e-10, 1e-300, 0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
      NodeParams q = p;
      q.*r.field = bad;
      try {
        validate(q);
        ADD_FAILURE() << r.name << " = " << bad << " accepted";
      } catch (const ParamError& e) {
        EXPECT_NE(std::string(e.what()).find(std::string("~") + r.name + " = "), std::string::npos) << e.what();
      }
    }
    NodeParams q = p;
    q.*r.field = r.min;
    EXPECT_NO_THROW(validate(q)) << r.name;
    EXPECT_NO_THROW(ros::WallDuration(1.0 / r.min)) << r.name;
  }
  EXPECT_ANY_THROW(ros::WallDuration(1.0 / 1e-10));  // what aborted the node before
}

// Wrong types are errors naming the parameter, the value as given and what was expected; an
// integer is a number (rosparam stores 1 as an integer), but a number is never a string or a
// boolean and a string never a number.
TEST(Params, WrongTypesNameParameterValueAndExpectedType) {
  using XmlRpc::XmlRpcValue;
  auto error = [](auto f) {
    try {
      f();
    } catch (const ParamError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(param_number("publish_rate", XmlRpcValue(100), "a number"), 100.0);
  EXPECT_EQ(param_number("publish_rate", XmlRpcValue(2.5), "a number"), 2.5);
  EXPECT_EQ(param_bool("paused", XmlRpcValue(true)), true);
  EXPECT_EQ(param_string("line_frame", XmlRpcValue(std::string("map")), "a frame id"), "map");
  EXPECT_EQ(param_integer("hil/realtime_priority", XmlRpcValue(5), "an integer"), 5);

  std::string e = error([] { param_number("publish_rate", XmlRpcValue(std::string("fast")), "a number in [1, 10000] Hz"); });
  EXPECT_NE(e.find("~publish_rate = 'fast' (a string)"), std::string::npos) << e;
  EXPECT_NE(e.find("expected a number in [1, 10000] Hz"), std::string::npos) << e;
  e = error([] { param_number("publish_rate", XmlRpcValue(true), "a number"); });
  EXPECT_NE(e.find("~publish_rate = true (a boolean)"), std::string::npos) << e;
  e = error([] { param_string("line_frame", XmlRpcValue(5), "a frame id"); });  // _line_frame:=5
  EXPECT_NE(e.find("~line_frame = 5 (an integer)"), std::string::npos) << e;
  EXPECT_NE(e.find("expected a frame id"), std::string::npos) << e;
  e = error([] { param_string("at_end", XmlRpcValue(1), "stop, loop or exit"); });  // _at_end:=1
  EXPECT_NE(e.find("~at_end = 1 (an integer)"), std::string::npos) << e;
  EXPECT_NE(e.find("stop, loop or exit"), std::string::npos) << e;
  e = error([] { param_bool("paused", XmlRpcValue(1)); });
  EXPECT_NE(e.find("~paused = 1 (an integer) rejected: expected true or false"), std::string::npos) << e;
  e = error([] { param_bool("paused", XmlRpcValue(std::string("yes"))); });
  EXPECT_NE(e.find("~paused = 'yes' (a string)"), std::string::npos) << e;
  e = error([] { param_integer("hil/realtime_priority", XmlRpcValue(5.5), "an integer in [0, 99]"); });
  EXPECT_NE(e.find("~hil/realtime_priority = 5.5 (a number)"), std::string::npos) << e;
  XmlRpcValue list;
  list.setSize(1);
  list[0] = 1;
  e = error([&] { param_number("vertical_scale", list, "a number"); });
  EXPECT_NE(e.find("~vertical_scale = a list"), std::string::npos) << e;
}

TEST(Params, UnknownParametersAreFoundAndTheClosestKnownNameSuggested) {
  const std::vector<std::string> known{"scene", "vertical_scale", "real_time_factor", "hil/rate", "publish_rate"};
  const std::vector<std::string> all{"/catenary_sim/scene",          "/catenary_sim/vertical_scal",
                                     "/catenary_sim/real_time_facter", "/catenary_sim/rate",
                                     "/catenary_sim/zzz",            "/catenary_sim_hil/foo",
                                     "/catenary_sim2/bar",           "/use_sim_time",
                                     "/catenary_sim/hil/rate"};
  const std::vector<std::string> unknown = unknown_parameters(all, "/catenary_sim", known);
  EXPECT_EQ(unknown, (std::vector<std::string>{"rate", "real_time_facter", "vertical_scal", "zzz"}));
  EXPECT_EQ(unknown_parameter_warning("vertical_scal", known),
            "unknown parameter ~vertical_scal (ignored); did you mean ~vertical_scale?");
  EXPECT_EQ(unknown_parameter_warning("real_time_facter", known),
            "unknown parameter ~real_time_facter (ignored); did you mean ~real_time_factor?");
  // A name without its group: the group's parameter.
  EXPECT_EQ(unknown_parameter_warning("rate", known), "unknown parameter ~rate (ignored); did you mean ~hil/rate?");
  // Nothing close: the known names are listed.
  const std::string w = unknown_parameter_warning("zzz", known);
  EXPECT_NE(w.find("unknown parameter ~zzz (ignored); known parameters: ~scene, ~vertical_scale"), std::string::npos) << w;
  EXPECT_EQ(w.find("did you mean"), std::string::npos) << w;
}

TEST_F(Fixture, StatisticsJsonHasPantographs) {
  PassRecorder rec(sim->model());
  const std::string j = statistics_json(sim->model(), sim->state(), rec.statistics(sim->model()), RunInfo{1.0, -1.0, 3});
  EXPECT_NE(j.find("\"pantographs\""), std::string::npos);
  EXPECT_NE(j.find("\"overruns\": 3"), std::string::npos);
}

// rviz turns the whole display to Error for a list marker sent with no points ("Points should not
// be empty"): no ADD of a LINE_LIST, LINE_STRIP, POINTS, CUBE_LIST, SPHERE_LIST or TRIANGLE_LIST
// may be empty, in any state: no dropper slack (the usual case), every dropper slack, an overlap,
// a moving force, a scene without droppers or steady arms, an external (HIL) pantograph.
TEST(Markers, NoListMarkerIsEverSentEmpty) {
  using visualization_msgs::Marker;
  auto check = [](const visualization_msgs::MarkerArray& arr, const std::string& what) {
    for (const Marker& mk : arr.markers) {
      const bool list = mk.type == Marker::LINE_LIST || mk.type == Marker::LINE_STRIP || mk.type == Marker::POINTS ||
                        mk.type == Marker::CUBE_LIST || mk.type == Marker::SPHERE_LIST || mk.type == Marker::TRIANGLE_LIST;
      if (list && mk.action == Marker::ADD) {
        EXPECT_FALSE(mk.points.empty()) << what << ": " << mk.ns << "/" << mk.id;
      }
    }
  };
  const std::string& dir = test_scenes::kConfigDir;
  for (const char* scene : {"reference_55m.yaml", "calpe_example.yaml", "reference_55m_hil.yaml", "reference_55m_two_sections.yaml"}) {
    Simulation sim(load_scene_file(dir + scene));
    MarkerOptions o;
    const auto idle = to_markers(sim.model(), sim.state(), ros::Time(1.0), o);
    check(idle, std::string(scene) + " at the start");
    // The slack droppers' marker is there, as a DELETE, when none is slack: it clears the last ones.
    bool slack_deleted = sim.model().droppers.empty();
    for (const Marker& mk : idle.markers)
      if (mk.ns == "droppers" && mk.id == 1) slack_deleted = mk.action == Marker::DELETE;
    EXPECT_TRUE(slack_deleted) << scene;
    State s = sim.state();
    std::fill(s.dropper_slack.begin(), s.dropper_slack.end(), 1);
    check(to_markers(sim.model(), s, ros::Time(1.0), o), std::string(scene) + " all droppers slack");
    for (int i = 0; i < 2000 && sim.step() == StepStatus::kOk; ++i) {
    }
    check(to_markers(sim.model(), sim.state(), ros::Time(2.0), o), std::string(scene) + " during the pass");
  }
  Simulation wire(load_scene_string(
      "line: {span_length: 50.0, span_count: 2}\ncontact_wire: {linear_mass: 1.35, tension: 20000.0}\n"
      "pantographs: [{name: f, type: moving_force, static_uplift: 100}]\ntrain: {speed: 50.0}\n"));
  check(to_markers(wire.model(), wire.state(), ros::Time(1.0), MarkerOptions{}), "a single wire (no droppers, no arms)");
}

// A 3-D line drawn in 3-D: the contact wire at its stagger at the supports, the head at the sway,
// the dot where the strip meets the wire at the contact point; ~lateral_scale stretches every
// lateral coordinate and width alike (x and z untouched), so the wire stays where it is on the strip.
TEST(Markers, ThreeDimensionalLineIsDrawnAcrossTheTrackAndStretchedAlike) {
  Simulation sim(load_scene_file(test_scenes::kReference3d,
                                 {"pantograph_head.sway.amplitude=0.05", "pantograph_head.sway.frequency=0.5"}));
  for (int i = 0; i < 800; ++i) ASSERT_EQ(sim.step(), StepStatus::kOk);
  const Model& m = sim.model();
  const State& s = sim.state();
  MarkerOptions o;
  o.shape_resolution = 0.0;
  const visualization_msgs::MarkerArray a = to_markers(m, s, ros::Time(1.0), o);
  o.lateral_scale = 7.0;
  const visualization_msgs::MarkerArray b = to_markers(m, s, ros::Time(1.0), o);
  ASSERT_EQ(a.markers.size(), b.markers.size());
  bool dot = false, wire = false;
  for (std::size_t k = 0; k < a.markers.size(); ++k) {
    const visualization_msgs::Marker &x = a.markers[k], &y = b.markers[k];
    ASSERT_EQ(x.points.size(), y.points.size()) << x.ns;
    for (std::size_t j = 0; j < x.points.size(); ++j) {
      EXPECT_EQ(x.points[j].x, y.points[j].x);
      EXPECT_EQ(x.points[j].z, y.points[j].z);
      EXPECT_NEAR(y.points[j].y, 7.0 * x.points[j].y, 1e-12) << x.ns;
    }
    EXPECT_NEAR(y.pose.position.y, 7.0 * x.pose.position.y, 1e-12) << x.ns;
    if (x.ns == "lateral_contact" && x.action == visualization_msgs::Marker::ADD) {
      ASSERT_EQ(x.points.size(), 1u);
      // wire minus pantograph = contact point on the strip: drawn at the pantograph's + that
      EXPECT_NEAR(x.points[0].y, s.lateral.pantograph_lateral[0] + s.lateral.collector_lateral[0], 1e-12);
      EXPECT_NEAR(y.scale.y, 7.0 * x.scale.y, 1e-12);
      dot = true;
    }
    if (x.ns == "pantograph_strips") {  // centred on the pantograph (its sway)
      EXPECT_NEAR(0.5 * (x.points[0].y + x.points[1].y), s.lateral.pantograph_lateral[0], 1e-12);
    }
    if (x.ns == "wires" && x.id == 0) {
      // At the supports (rigid registration in plan here: springs of 2e5 N/m, within a few mm).
      for (const geometry_msgs::Point& p : x.points)
        for (int k2 = 1; k2 < 10; ++k2)
          if (std::fabs(p.x - 55.0 * k2) < 1e-9) {
            EXPECT_NEAR(p.y, k2 % 2 ? -0.3 : 0.3, 0.02) << "support " << k2;
            wire = true;
          }
    }
  }
  EXPECT_TRUE(dot);
  EXPECT_TRUE(wire);
}

namespace {

// FNV-1a over the serialized message (the bytes rviz receives): any change of any field moves it.
std::uint64_t wire_bytes_hash(const visualization_msgs::MarkerArray& a) {
  const std::uint32_t n = ros::serialization::serializationLength(a);
  std::vector<std::uint8_t> bytes(n);
  ros::serialization::OStream out(bytes.data(), n);
  ros::serialization::serialize(out, a);
  std::uint64_t h = 1469598103934665603ull;
  for (std::uint8_t b : bytes) h = (h ^ b) * 1099511628211ull;
  return h;
}

}  // namespace

// What holds a wire is drawn on it at any ~shape_resolution: every support node (a steady arm's,
// a bracket's, a bridle's middle) and both ends (clamps, anchors) are among the stations sampled,
// on a bridled trolley wire (a bridle of 8 m sampled at 5 m skipped its middle, leaving the
// bracket's end in the air) and on an overlap whose supports are off the sampling's whole metres.
TEST(Markers, EveryWireIsSampledWhereItIsHeld) {
  for (const char* file : {"trolley_wire_bridle_3d.yaml", "calpe_example.yaml"}) {
    Simulation sim(load_scene_file(test_scenes::scene_path(file)));
    const Model& m = sim.model();
    for (double resolution : {1.0, 5.0, 100.0}) {
      const WireShapeArray shape = to_wire_shape(m, sim.state(), resolution, ros::Time(1.0), "line");
      ASSERT_EQ(shape.wires.size(), m.wires.size());
      for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
        const Wire& w = m.wires[wi];
        const std::vector<double>& at = shape.wires[wi].stations;
        std::vector<int> held = w.support_nodes;
        held.push_back(0);
        held.push_back(w.nodes() - 1);
        for (int node : held)
          EXPECT_TRUE(std::find(at.begin(), at.end(), w.x[node]) != at.end())
              << file << ": " << w.name << " at " << w.x[node] << " m, resolution " << resolution << " m";
      }
    }
  }
}

// The drawing must not move when its code is rearranged: the markers of scenes that take every
// branch (static parts, slack droppers, two heads, an overlap's per-wire label, a 3-D line with
// sway stretched across the track, two pantographs, an external pantograph, a moving force) are
// hashed byte for byte, like the golden passes (test_golden_hashes). Each drawing was checked by
// the tests above and in rviz; a change of the drawing changes a hash on purpose, and the commit
// that records the new hash says why. On a mismatch the message prints the new hash.
TEST(Markers, DrawingOfTheReferenceScenesIsUnchanged) {
  const std::string dir = std::string(CATENARY_SIM_SOURCE_DIR) + "/config/";
  struct Case {
    const char* name;
    std::string scene;
    std::vector<std::string> overrides;
    int steps;  // < 0: to the station -steps m
    double lateral_scale;
    bool all_slack;
    std::uint64_t expected;
  };
  const std::vector<Case> cases = {
      {"reference", dir + "reference_55m.yaml", {}, 2000, 1.0, false, 0xef496125ab41a9acull},
      {"reference, every dropper slack", dir + "reference_55m.yaml", {}, 2000, 1.0, true, 0x4eeb7da29370cb34ull},
      {"two heads", dir + "reference_55m_two_heads.yaml", {}, 3000, 1.0, false, 0x2c17b1565032233cull},
      {"overlap", dir + "calpe_example.yaml", {}, -50, 1.0, false, 0xa333068db0d0acf6ull},  // to 50 m: under both wires
      {"3-D line with sway", dir + "reference_55m_3d.yaml",
       {"pantograph_head.sway.amplitude=0.05", "pantograph_head.sway.frequency=0.5"}, 800, 7.0, false, 0xa76580d5ec007007ull},
      {"two pantographs", dir + "reference_55m_two_pantographs.yaml", {}, 3000, 1.0, false, 0xcc0af6d3b9d7932aull},
      {"external pantograph", dir + "reference_55m_hil.yaml", {}, 0, 1.0, false, 0x981d981f3f1990f0ull},
      {"moving force", dir + "reference_55m.yaml", {"pantographs=[{name: force, type: moving_force, static_uplift: 120}]"}, 1000, 1.0, false, 0x29ff643478ab0a95ull},
  };
  for (const Case& c : cases) {
    Simulation sim(load_scene_file(c.scene, c.overrides));
    for (int i = 0; i < c.steps; ++i) ASSERT_EQ(sim.step(), StepStatus::kOk) << c.name;
    if (c.steps < 0) step_to(sim, -c.steps);
    State s = sim.state();
    if (c.all_slack) std::fill(s.dropper_slack.begin(), s.dropper_slack.end(), 1);
    MarkerOptions o;
    o.lateral_scale = c.lateral_scale;
    const std::uint64_t h = wire_bytes_hash(to_markers(sim.model(), s, ros::Time(1.0), o));
    char got[32];
    std::snprintf(got, sizeof got, "0x%016llxull", static_cast<unsigned long long>(h));
    EXPECT_EQ(h, c.expected) << c.name << ": the markers hash to " << got;
  }
}
