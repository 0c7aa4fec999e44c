// Pure functions from the core's Model/State to ROS messages, markers and transforms, plus the
// pacing arithmetic and the statistics JSON. No node handle, no clock: gtest-able without a master.
#pragma once

#include <geometry_msgs/TransformStamped.h>
#include <ros/time.h>
#include <visualization_msgs/MarkerArray.h>

#include <cstdint>
#include <string>
#include <vector>

#include "catenary_sim/ContactForceArray.h"
#include "catenary_sim/LateralContactArray.h"
#include "catenary_sim/LineState.h"
#include "catenary_sim/PantographStateArray.h"
#include "catenary_sim/WireShapeArray.h"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/scene/scene.hpp"
#include "catenary_sim/core/engine/state.hpp"
#include "catenary_sim/core/output/statistics.hpp"

namespace catenary_sim {
namespace ros_layer {

// Stamp of a simulation time: ros::Time(sim_time + offset). The offset is fixed for the life of
// the node; the core keeps its clock running across resets, so stamps never go backwards.
ros::Time sim_stamp(double sim_time, double offset);

// A cmd/train_speed command (m/s), as the nodes check it before the core's set_target_speed:
// empty when allowed (train_speed_limit of the scene), else the message naming the topic, the
// value and the range, e.g. "cmd/train_speed = 200 m/s rejected: allowed 0 to below 127.7 m/s
// (459.6 km/h), the contact wire's wave speed ..." (%g numbers; the core's own message has
// std::to_string's "200.000000").
std::string speed_command_error(const Scene& scene, double speed_mps);

ContactForceArray to_contact_force(const Model& m, const State& s, const ros::Time& stamp, const std::string& frame);
PantographStateArray to_pantograph_state(const Model& m, const State& s, const ros::Time& stamp,
                                         const std::string& frame);
// Samples every wire at about `resolution` m (0: every node); the last node is always included.
WireShapeArray to_wire_shape(const Model& m, const State& s, double resolution, const ros::Time& stamp,
                             const std::string& frame);

// The scene of a pass as the node publishes it (latched ~scene_yaml, std_msgs/String, recorded
// with the pass): a first line "# catenary_sim scene: PATH" (the file's absolute path, for the
// files a scene names relative to itself), a line "# catenary_sim set: KEY=VALUE" per override
// (simulate_pass --set), then the file's text. Throws SceneError if the file cannot be read.
std::string scene_yaml_message(const std::string& path, const std::vector<std::string>& overrides = {});
// The scene of such a message (its relative files looked up beside PATH, its overrides applied);
// throws SceneError.
Scene scene_from_message(const std::string& text);

// Slack droppers and the steady arms within a span of a pantograph: their uplift now and the
// largest so far, as the pass's recorder has it at every step (stats.json's steady_arms are the
// same values over the analysis section).
LineState to_line_state(const Model& m, const State& s, const PassRecorder& recorder, const ros::Time& stamp,
                        const std::string& frame);

// Per collector, where its strip meets the contact wire across the track (the contact point's
// lateral position on the strip, the wire's and the pantograph's); no contacts on a 2-D line.
LateralContactArray to_lateral_contact(const Model& m, const State& s, const ros::Time& stamp,
                                       const std::string& frame);

// Design height (m) of a wire's vertical DOF; NaN if `dof` is not a wire's vertical DOF.
double wire_dof_design_height(const Model& m, int dof);

// Design height (m) of the contact wire under a pantograph now: under each collector the contact
// wire with the lowest design height there (the one the head meets first; in an overlap, the lower
// of the two), averaged over the collectors; the scene's contact_wire_height when no collector is
// under a contact wire.
double contact_design_height(const Model& m, const State& s, int pantograph);

// Height (m) at which the markers draw a pantograph head with displacements exaggerated k times:
// d + k (head - d), d = contact_design_height, the same rule as for the wires (design + k u), so
// that a head in contact is drawn on the wire it touches (k x the contact spring's compression,
// a few cm, above it). A moving force is drawn on the displaced wire under it.
double drawn_head_height(const Model& m, const State& s, int pantograph, double k);
// The same for one head of a pantograph with several heads, about the design height of the wire
// over that head's strips (a chain without heads: as above).
double drawn_head_height(const Model& m, const State& s, int pantograph, int head, double k);
// Marker ids in namespace pantograph_head: head 0 has the pantograph's index p, head h > 0
// kHeadIdStride h + p.
constexpr int kHeadIdStride = 1000;

// Frame ids of the train (x = train front), of a pantograph head, and of the view frame the rviz
// camera follows (train_view: also at the train front, but sent with each marker message only).
std::string train_frame_id();
std::string head_frame_id(const Model& m, int pantograph);
std::string view_frame_id();

// line -> train_view at the train front, for the stamp of a marker message: the camera that follows
// it moves exactly when the markers do, not at the tf rate between two marker messages.
geometry_msgs::TransformStamped to_view_transform(const State& s, const ros::Time& stamp,
                                                  const std::string& line_frame);
// train_view and, on a train with several pantographs, line -> train_view_<name> at each
// pantograph's station, sent the same way: an rviz camera whose Target Frame is one of them
// follows that pantograph. train_view is at the front, or with `followed` >= 0 at that
// pantograph's station (~view_pantograph): the default view and the strip chart then go with it.
std::vector<geometry_msgs::TransformStamped> to_view_transforms(const Model& m, const State& s, const ros::Time& stamp,
                                                                const std::string& line_frame, int followed = -1);
// The index of the pantograph named `name` for to_view_transforms (empty: -1, the front); another
// name throws std::invalid_argument naming `parameter`, the value and the scene's pantographs.
int view_pantograph_index(const Model& m, const std::string& name, const std::string& parameter);

// line -> train (at the train front, on the rail) and train -> one frame per pantograph head (at
// the head's true absolute height, not exaggerated; a moving force sits at the contact-wire
// design height).
std::vector<geometry_msgs::TransformStamped> to_transforms(const Model& m, const State& s, const ros::Time& stamp,
                                                           const std::string& line_frame);

struct MarkerOptions {
  std::string frame = "line";
  double vertical_scale = 10.0;   // displacements multiplied by this
  // Every lateral coordinate and width multiplied by this (a y axis stretched like a plot's, so
  // that a 0.3 m stagger shows from above; the head and the wire keep their relation). 1: true.
  double lateral_scale = 1.0;
  double shape_resolution = 1.0;  // m between line-strip points (0: every node)
  bool include_static = true;     // masts and steady arms (constant parts)
};

// The contact-force strip chart drawn in rviz beside the line, to see the force as it happens: the last
// `window` seconds of one or more series (per pantograph, and per contact wire in overlaps), in a
// panel in the train-following frame, with a force axis (ticks every 100 N), a time axis, a legend,
// the statistics so far and a heads-up line (station, span, time, real-time factor, scale).
// A contact wire's name shortened for labels: "contact_wire_s1" -> "cw_s1".
std::string label_wire_name(const std::string& name);

struct ChartSeries {
  std::string name;
  std::vector<double> force;  // N, one per sample of ChartData::time
};
struct ChartData {
  std::vector<double> time;          // s, simulated, increasing
  std::vector<ChartSeries> series;
  std::vector<std::string> stats;    // one line per pantograph: "leading: mean 99 N, std 41 N, ..."
  std::string heading;               // the heads-up line
};
struct ChartOptions {
  std::string frame = "train_view";  // follows the train (to_view_transform)
  double window = 5.0;               // s shown
  // The panel faces the default view of config/catenary_sim.rviz (an orbit 16 m from (-5, 0, 6) in
  // train_view at yaw -0.45): its time axis runs along (dir_x, dir_y), the camera's right, and it
  // sits in the upper left of that view, clear of the line and the head.
  double origin_x = -8.6, origin_y = -7.2, z_bottom = 7.7;  // m: the bottom-left corner
  double dir_x = 0.442, dir_y = 0.897;                       // unit, horizontal
  double width = 8.0, height = 2.6;                          // m
  double text = 0.36;                                        // m, text height
  double force_max = 300.0;          // N at the top (grows to the next 100 N above the data)
};
visualization_msgs::MarkerArray to_strip_chart(const ChartData& d, const ros::Time& stamp, const ChartOptions& o);

// Wire line strips, droppers (slack in red), masts and steady arms, pantograph head and frame,
// contact-force arrows (1 m per 100 N) and a white text label (0.5 m) with the force, per contact
// wire under the pantograph when the line has several, and the speed. Vertical displacements are
// exaggerated by vertical_scale about the design geometry, the heads about the design height of
// the contact wire under them (drawn_head_height). On a 3-D line everything sits at its lateral
// position in the track's frame (line frame y, true scale, not exaggerated: on a curve the track
// is drawn straightened out): the wires' zigzag and blow-off, the head at its sway with the scene's
// working and horn widths, and a dot where each strip meets the wire (yellow, red off the working
// width), the force arrow there and the contact point across the strip in the label.
visualization_msgs::MarkerArray to_markers(const Model& m, const State& s, const ros::Time& stamp,
                                           const MarkerOptions& o);

// Pacing: the number of steps of `dt` due so that the simulation time reaches
// sim_anchor + rtf * wall_elapsed, given that sim_done has already been simulated since the
// anchor. Never negative; dt is never stretched.
std::int64_t steps_due(double wall_elapsed, double real_time_factor, double dt, double sim_done);

}  // namespace ros_layer
}  // namespace catenary_sim
