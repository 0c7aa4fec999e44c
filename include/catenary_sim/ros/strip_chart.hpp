// The contact-force strip chart in rviz (ChartData, to_strip_chart): its samples over the last
// window of simulated time and the running statistics of the pass, for the pass node and the
// hardware-in-the-loop node alike.
#pragma once

#include <visualization_msgs/MarkerArray.h>

#include <string>
#include <vector>

#include "catenary_sim/core/engine/state.hpp"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/ros/markers.hpp"

namespace catenary_sim {
namespace ros_layer {

// The heads-up line's start: the train front's station, its span (counted from 1, as a railway
// engineer counts them) and the simulated time, e.g. "x 312.4 m  span 7  t 4.12 s".
std::string heads_up_position(const Model& m, const State& s);

class StripChart {
 public:
  StripChart() = default;

  // Forgets the samples and the statistics (a new pass); window: s of simulated time shown.
  void clear(double window);
  // Adds the state's contact forces (per pantograph and, in overlaps, per contact wire) once per
  // simulated time; drops the samples older than the window.
  void sample(const Model& m, const State& s);
  // True when at least `spacing` of simulated time has passed since the last sample (or none yet).
  bool due(double time, double spacing) const { return last_time_ < 0.0 || time - last_time_ >= spacing; }
  bool empty() const { return last_time_ < 0.0; }

  // The chart's markers with `heading` as its heads-up line and one statistics line per
  // pantograph (unfiltered, so far: the filtered ones need the whole pass, zero-phase).
  visualization_msgs::MarkerArray markers(const Model& m, const std::string& heading, const ros::Time& stamp);

 private:
  struct Running {  // unfiltered contact force so far in this pass
    double n = 0, sum = 0, sum2 = 0, max = -1e300, min = 1e300;
  };
  double window_ = 5.0;
  ChartData data_;
  std::vector<Running> running_;  // per pantograph
  double last_time_ = -1.0;
};

}  // namespace ros_layer
}  // namespace catenary_sim
