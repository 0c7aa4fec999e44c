// Replay of a recording (replay.hpp): the state rebuilt from the recorded messages draws the same
// markers as the live state. Pure: no master.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/ros/conversions.hpp"
#include "catenary_sim/ros/markers.hpp"
#include "catenary_sim/ros/replay.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;
using namespace catenary_sim::ros_layer;

namespace {

using test_scenes::scene_path;

// Marker coordinates are rebuilt as (design + u) - design, which rounds u by a few ulp of the
// height (~5 m: 1e-15 m) before the vertical scale (10): 1e-9 m is far above that rounding and far
// below anything drawn (1 mm).
constexpr double kTol = 1e-9;

void expect_same_point(const geometry_msgs::Point& a, const geometry_msgs::Point& b, const std::string& what) {
  EXPECT_NEAR(a.x, b.x, kTol) << what;
  EXPECT_NEAR(a.y, b.y, kTol) << what;
  EXPECT_NEAR(a.z, b.z, kTol) << what;
}

// Every marker of `live` in `replay`, in the same order, with the same points, pose, colour and text.
void expect_same_markers(const visualization_msgs::MarkerArray& live, const visualization_msgs::MarkerArray& replay,
                         bool droppers_colour) {
  ASSERT_EQ(live.markers.size(), replay.markers.size());
  for (std::size_t i = 0; i < live.markers.size(); ++i) {
    const auto& a = live.markers[i];
    const auto& b = replay.markers[i];
    const std::string what = a.ns + "/" + std::to_string(a.id);
    ASSERT_EQ(a.ns, b.ns);
    ASSERT_EQ(a.id, b.id);
    EXPECT_EQ(a.type, b.type) << what;
    EXPECT_EQ(a.header.frame_id, b.header.frame_id) << what;
    EXPECT_EQ(a.text, b.text) << what;
    expect_same_point(a.pose.position, b.pose.position, what);
    if (a.ns == "droppers" && !droppers_colour) continue;  // compared as a whole by the caller
    EXPECT_EQ(a.color, b.color) << what;
    ASSERT_EQ(a.points.size(), b.points.size()) << what;
    for (std::size_t k = 0; k < a.points.size(); ++k) expect_same_point(a.points[k], b.points[k], what);
  }
}

struct Rebuilt {
  std::string error;
  State state;
};

Rebuilt rebuild(const Model& m, const State& s, double resolution) {
  const ros::Time stamp(1.0 + s.time);  // a stamp offset, as simulate_pass --bag writes
  Rebuilt r{"", make_state(m)};
  r.error = state_from_messages(m, to_wire_shape(m, s, resolution, stamp, "line"),
                                to_pantograph_state(m, s, stamp, "line"), to_contact_force(m, s, stamp, "line"),
                                &r.state);
  return r;
}

// Runs `steps` steps, then checks that the markers drawn from the recorded messages (every node)
// are the live markers.
void check_scene(const char* name, int steps, bool until_offset_moves = false) {
  SCOPED_TRACE(name);
  Simulation sim(load_scene_file(scene_path(name)));
  const Model& m = sim.model();
  const double offset0 = sim.state().line_offset;
  for (int i = 0; i < steps || (until_offset_moves && sim.state().line_offset == offset0 && i < 200000); ++i)
    ASSERT_EQ(sim.step(), StepStatus::kOk);
  const State& s = sim.state();
  if (until_offset_moves) {
    ASSERT_NE(s.line_offset, offset0) << "the block never moved";
  }
  const Rebuilt r = rebuild(m, s, 0.0);
  ASSERT_EQ(r.error, "");
  EXPECT_DOUBLE_EQ(r.state.line_offset, s.line_offset);
  EXPECT_NEAR(r.state.front, s.front, 1e-9);
  EXPECT_EQ(r.state.time, s.time);
  MarkerOptions o;
  o.shape_resolution = 1.0;
  // Droppers: the live flags come from inside the last step (its start displacements for the
  // explicit scheme, the active set for the implicit one), the replay's from the recorded
  // displacements at its end; they differ only for a dropper that switched in that step.
  int slack = 0, differ = 0;
  for (std::size_t d = 0; d < m.droppers.size(); ++d) {
    slack += s.dropper_slack[d];
    differ += s.dropper_slack[d] != r.state.dropper_slack[d];
  }
  // At these instants (fixed dt, bit-reproducible) no dropper switched in the last step, so the
  // colours must agree too; should a core change make one switch exactly there, pick another step.
  EXPECT_EQ(differ, 0) << "of " << slack << " slack droppers";
  expect_same_markers(to_markers(m, s, ros::Time(1.0 + s.time), o), to_markers(m, r.state, ros::Time(1.0 + s.time), o),
                      true);
}

}  // namespace

TEST(Replay, MarkersFromMessagesAreTheLiveMarkers) { check_scene("reference_55m.yaml", 3000); }

TEST(Replay, TwoPantographsAndTwoContactWires) {
  check_scene("reference_55m_two_pantographs.yaml", 3000);
  check_scene("reference_55m_two_sections.yaml", 3000);
}

// A 3-D line (stagger, gusty cross wind): the wires' lateral positions travel in wire_shape, the
// sway and the contact points across the strips follow from them; every marker is the live one.
TEST(Replay, ThreeDimensionalLineDrawsTheLiveMarkers) { check_scene("reference_55m_3d.yaml", 3000); }

TEST(Replay, EndlessLineKeepsTheLineOffset) { check_scene("reference_55m_endless.yaml", 0, true); }

TEST(Replay, RecordingAtOneMetreDrawsTheSameWires) {
  // pass.launch records wire_shape at ~shape_resolution 1 m; the markers sample the wires at the
  // same nodes, so the wire strips are exact; droppers and heads between samples are interpolated.
  Simulation sim(load_scene_file(scene_path("reference_55m.yaml")));
  for (int i = 0; i < 3000; ++i) ASSERT_EQ(sim.step(), StepStatus::kOk);
  const Model& m = sim.model();
  const Rebuilt r = rebuild(m, sim.state(), 1.0);
  ASSERT_EQ(r.error, "");
  MarkerOptions o;
  o.shape_resolution = 1.0;
  const auto live = to_markers(m, sim.state(), ros::Time(1), o), replay = to_markers(m, r.state, ros::Time(1), o);
  ASSERT_EQ(live.markers.size(), replay.markers.size());
  int wires = 0;
  for (std::size_t i = 0; i < live.markers.size(); ++i) {
    if (live.markers[i].ns != "wires") continue;
    ++wires;
    ASSERT_EQ(live.markers[i].points.size(), replay.markers[i].points.size());
    for (std::size_t k = 0; k < live.markers[i].points.size(); ++k)
      expect_same_point(live.markers[i].points[k], replay.markers[i].points[k], "wire");
  }
  EXPECT_EQ(wires, static_cast<int>(m.wires.size()));
}

TEST(Replay, CompressedDropperIsDrawnSlack) {
  // A contact wire lifted 0.3 m at a dropper (above its ~100 N static tension / stiffness) compresses
  // it: the replay must draw that dropper in the slack (red) list.
  Simulation sim(load_scene_file(scene_path("reference_55m.yaml")));
  const Model& m = sim.model();
  State s = sim.state();
  const std::size_t d = m.droppers.size() / 2;
  ASSERT_LT(m.droppers[d].static_tension / m.droppers[d].stiffness, 0.3);
  s.u[m.droppers[d].contact_dof] += 0.3;
  const Rebuilt r = rebuild(m, s, 0.0);
  ASSERT_EQ(r.error, "");
  for (std::size_t k = 0; k < m.droppers.size(); ++k) EXPECT_EQ(r.state.dropper_slack[k], k == d) << "dropper " << k;
  const auto mk = to_markers(m, r.state, ros::Time(1), MarkerOptions{});
  for (const auto& x : mk.markers)
    if (x.ns == "droppers") {
      EXPECT_EQ(x.points.size(), x.id == 1 ? 2u : 2 * (m.droppers.size() - 1)) << x.id;
    }
}

TEST(Replay, RecordingOfAnotherSceneIsRefusedWithTheField) {
  Simulation one(load_scene_file(scene_path("reference_55m.yaml")));
  Simulation two(load_scene_file(scene_path("reference_55m_two_sections.yaml")));
  const ros::Time stamp(1);
  const State& s = one.state();
  const Model& m1 = one.model();
  State out = make_state(two.model());
  const std::string e = state_from_messages(two.model(), to_wire_shape(m1, s, 1.0, stamp, "line"),
                                            to_pantograph_state(m1, s, stamp, "line"),
                                            to_contact_force(m1, s, stamp, "line"), &out);
  EXPECT_NE(e.find("wire_shape"), std::string::npos) << e;
  EXPECT_NE(e.find("is ~scene the scene of the recording?"), std::string::npos) << e;

  // A recording of the scene with one pantograph state missing.
  Simulation pair(load_scene_file(scene_path("reference_55m_two_pantographs.yaml")));
  const Model& m2 = pair.model();
  PantographStateArray ps = to_pantograph_state(m2, pair.state(), stamp, "line");
  ps.pantographs.pop_back();
  State out2 = make_state(m2);
  const std::string e2 = state_from_messages(m2, to_wire_shape(m2, pair.state(), 1.0, stamp, "line"), ps,
                                             to_contact_force(m2, pair.state(), stamp, "line"), &out2);
  EXPECT_NE(e2.find("pantograph_state has 1 pantographs, the scene 2"), std::string::npos) << e2;
}

// A NaN anywhere in a recording is refused by the field that holds it, never drawn (the wires'
// samples were checked; the train's, the pantographs' and the contact forces' were drawn as NaN).
TEST(Replay, ANaNInTheRecordingIsRefusedByItsField) {
  Simulation sim(load_scene_file(scene_path("reference_55m.yaml")));
  for (int k = 0; k < 500; ++k) ASSERT_EQ(sim.step(), StepStatus::kOk);
  const Model& m = sim.model();
  const ros::Time stamp(1.0 + sim.state().time);
  const WireShapeArray shape = to_wire_shape(m, sim.state(), 1.0, stamp, "line");
  const PantographStateArray state = to_pantograph_state(m, sim.state(), stamp, "line");
  const ContactForceArray force = to_contact_force(m, sim.state(), stamp, "line");
  const double nan = std::nan("");
  auto refusal = [&](auto&& spoil) {
    PantographStateArray ps = state;
    ContactForceArray cf = force;
    spoil(ps, cf);
    State out = make_state(m);
    return state_from_messages(m, shape, ps, cf, &out);
  };
  State out = make_state(m);
  ASSERT_EQ(state_from_messages(m, shape, state, force, &out), "");
  const std::vector<std::pair<std::string, std::function<void(PantographStateArray&, ContactForceArray&)>>> cases = {
      {"pantograph_state.train_front", [&](PantographStateArray& p, ContactForceArray&) { p.train_front = nan; }},
      {"pantograph_state.sim_time", [&](PantographStateArray& p, ContactForceArray&) { p.sim_time = nan; }},
      {"pantograph_state.speed", [&](PantographStateArray& p, ContactForceArray&) { p.speed = nan; }},
      {"pantograph_state.pantographs[0].displacement/velocity[1]",
       [&](PantographStateArray& p, ContactForceArray&) { p.pantographs[0].displacement[1] = nan; }},
      {"pantograph_state.pantographs[0].displacement/velocity[0]",
       [&](PantographStateArray& p, ContactForceArray&) { p.pantographs[0].velocity[0] = nan; }},
      {"pantograph_state.pantographs[0].uplift", [&](PantographStateArray& p, ContactForceArray&) { p.pantographs[0].uplift = nan; }},
      {"contact_force.pantographs[0].wire_forces[0]", [&](PantographStateArray&, ContactForceArray& c) { c.pantographs[0].wire_forces[0] = nan; }},
  };
  for (const auto& [field, spoil] : cases) {
    const std::string e = refusal(spoil);
    EXPECT_EQ(e.rfind(field, 0), 0u) << field << ": " << e;
    EXPECT_NE(e.find("finite"), std::string::npos) << e;
  }
  // A finite height no pass can have written (a pass stops at numerics.divergence_limit, 5 m).
  WireShapeArray far = shape;
  far.wires[1].heights[3] = 1e300;
  const std::string e = state_from_messages(m, far, state, force, &out);
  EXPECT_EQ(e.rfind("wire_shape.wires[1].heights[3] = 1e+300 m", 0), 0u) << e;
  EXPECT_NE(e.find("divergence_limit"), std::string::npos) << e;
  far.wires[1].heights[3] = shape.wires[1].heights[3] + 4.9;  // within it: drawn
  EXPECT_EQ(state_from_messages(m, far, state, force, &out), "");
}

// A replay's ~scene that differs from the recording's only where the messages do not show it
// (wire names, node counts and spans the same) is found by its design: a bridle's tension (its V
// hangs higher), a compound line's auxiliary height, the same scene is no difference.
TEST(Replay, AGivenSceneThatIsNotTheRecordingsIsNamed) {
  auto model = [](const char* file, const std::vector<std::string>& o) {
    return build_model(load_scene_file(scene_path(file), o));
  };
  EXPECT_EQ(scene_difference(model("trolley_wire_bridle.yaml", {}), model("trolley_wire_bridle.yaml", {})), "");
  // A recording at another rung (the fast rung's mesh, the replay's finer one) is the same line,
  // on every shipped line of one kind or another.
  for (const char* file : {"reference_55m.yaml", "reference_55m_3d_hinged_arms.yaml", "reference_55m_stitched.yaml",
                           "compound_catenary.yaml", "rigid_conductor_rail.yaml", "trolley_wire.yaml",
                           "trolley_wire_bridle.yaml", "catenary_to_rigid_rail.yaml", "catenary_to_trolley_wire.yaml",
                           "stitched_catenary_to_rigid_rail.yaml", "calpe_example.yaml"})
    EXPECT_EQ(scene_difference(model(file, {}), model(file, {"numerics.preset=fast"})), "") << file;
  const std::string bridle = scene_difference(model("trolley_wire_bridle.yaml", {"bridle.tension=3000"}),
                                              model("trolley_wire_bridle.yaml", {}));
  EXPECT_NE(bridle.find("wire 'bridle"), std::string::npos) << bridle;
  EXPECT_NE(bridle.find("in the recording's scene at"), std::string::npos) << bridle;
  const std::string compound = scene_difference(model("compound_catenary.yaml", {"auxiliary_messenger.height=0.3"}),
                                                model("compound_catenary.yaml", {}));
  EXPECT_NE(compound.find("designed at"), std::string::npos) << compound;
  const std::string spacing = scene_difference(model("trolley_wire.yaml", {"line.span_length=20", "line.span_count=15"}),
                                               model("trolley_wire.yaml", {}));
  EXPECT_NE(spacing.find("support"), std::string::npos) << spacing;
}

// The scene a recording carries (the node's ~scene_yaml, simulate_pass's bag): the same model as
// the file with its overrides, so that the replay draws without a scene argument. Here with a
// --set that changes the geometry (6 spans instead of 10): the message must carry it.
TEST(Replay, SceneMessageGivesTheSceneOfTheRecording) {
  const std::string path = scene_path("reference_55m.yaml");
  const std::vector<std::string> set{"line.span_count=6"};
  const Model file = build_model(load_scene_file(path, set));
  const Model carried = build_model(scene_from_message(scene_yaml_message(path, set)));
  EXPECT_EQ(carried.scene.name, file.scene.name);
  EXPECT_EQ(carried.n_dof, file.n_dof);
  EXPECT_EQ(carried.support_x, file.support_x);
  EXPECT_EQ(carried.support_x.size(), 7u);  // 6 spans
  // A file that cannot be read is the scene's error, not an empty message.
  EXPECT_THROW(scene_yaml_message("/nonexistent_catenary_sim_dir/s.yaml"), SceneError);
  // A value written over several lines (a shell's $'[2,\n 4]') stays within the comments: the
  // message is one YAML document and carries the value whole.
  const std::string stitched = scene_path("reference_55m_stitched.yaml");
  const std::vector<std::string> lines{"stitch_wire.at_supports=[2,\n 4]", "line.span_count=6"};
  const Model two_lines = build_model(scene_from_message(scene_yaml_message(stitched, lines)));
  const Model given = build_model(load_scene_file(stitched, lines));
  EXPECT_EQ(two_lines.n_dof, given.n_dof);
  EXPECT_EQ(two_lines.scene.sections.at(0).stitch_wire->at_supports, (std::vector<int>{2, 4}));
}
