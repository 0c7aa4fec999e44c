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
// (simulate_pass --set; a value's further lines each on a line "# catenary_sim set+ ..."), then
// the file's text. Throws SceneError if the file cannot be read.
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

// Pacing: the number of steps of `dt` due so that the simulation time reaches
// sim_anchor + rtf * wall_elapsed, given that sim_done has already been simulated since the
// anchor. Never negative; dt is never stretched.
std::int64_t steps_due(double wall_elapsed, double real_time_factor, double dt, double sim_done);

}  // namespace ros_layer
}  // namespace catenary_sim
