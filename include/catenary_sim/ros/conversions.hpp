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
#include "catenary_sim/PantographStateArray.h"
#include "catenary_sim/WireShapeArray.h"
#include "catenary_sim/core/model.hpp"
#include "catenary_sim/core/state.hpp"
#include "catenary_sim/core/statistics.hpp"

namespace catenary_sim {
namespace ros_layer {

// Stamp of a simulation time: ros::Time(sim_time + offset). The offset is fixed for the life of
// the node; the core keeps its clock running across resets, so stamps never go backwards.
ros::Time sim_stamp(double sim_time, double offset);

ContactForceArray to_contact_force(const Model& m, const State& s, const ros::Time& stamp, const std::string& frame);
PantographStateArray to_pantograph_state(const Model& m, const State& s, const ros::Time& stamp,
                                         const std::string& frame);
// Samples every wire at about `resolution` m (0: every node); the last node is always included.
WireShapeArray to_wire_shape(const Model& m, const State& s, double resolution, const ros::Time& stamp,
                             const std::string& frame);

// Design height (m) of a wire's vertical DOF; NaN if `dof` is not a wire's vertical DOF.
double wire_dof_design_height(const Model& m, int dof);

// Frame ids of the train (x = train front) and of a pantograph head.
std::string train_frame_id();
std::string head_frame_id(const Model& m, int pantograph);

// line -> train (at the train front, on the rail) and train -> one frame per pantograph head (at
// the head's true absolute height, not exaggerated; a moving force sits at the contact-wire
// design height).
std::vector<geometry_msgs::TransformStamped> to_transforms(const Model& m, const State& s, const ros::Time& stamp,
                                                           const std::string& line_frame);

struct MarkerOptions {
  std::string frame = "line";
  double vertical_scale = 10.0;   // displacements multiplied by this
  double shape_resolution = 1.0;  // m between line-strip points (0: every node)
  bool include_static = true;     // masts and steady arms (constant parts)
};

// Wire line strips, droppers (slack in red), masts and steady arms, pantograph head and frame,
// contact-force arrows (1 mm per N... scaled 1 m per 200 N) and a text label with speed and force.
// Vertical displacements are exaggerated by vertical_scale about the design geometry.
visualization_msgs::MarkerArray to_markers(const Model& m, const State& s, const ros::Time& stamp,
                                           const MarkerOptions& o);

// Pacing: the number of steps of `dt` due so that the simulation time reaches
// sim_anchor + rtf * wall_elapsed, given that sim_done has already been simulated since the
// anchor. Never negative; dt is never stretched.
std::int64_t steps_due(double wall_elapsed, double real_time_factor, double dt, double sim_done);

}  // namespace ros_layer
}  // namespace catenary_sim
