// The rviz drawing of a pass from the core's Model/State: the line, the pantographs and the
// contact-force strip chart, as visualization_msgs markers. Pure: no node handle, no clock;
// gtest-able without a master.
#pragma once

#include <ros/time.h>
#include <visualization_msgs/MarkerArray.h>

#include <string>
#include <vector>

#include "catenary_sim/core/engine/state.hpp"
#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {
namespace ros_layer {

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

}  // namespace ros_layer
}  // namespace catenary_sim
