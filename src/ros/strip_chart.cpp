#include "catenary_sim/ros/strip_chart.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace catenary_sim {
namespace ros_layer {
namespace {
// m the strip chart's panel rises for a label of three lines (ChartOptions::z_bottom): a 0.6 m
// line at the label, 16 m from the camera, spans about as much as 1 m at the panel, farther away.
constexpr double kThirdLabelLineLift = 1.0;
// Span of the train front along the line, counted from 0 (an endless line's spans go on).
long span_along_line(const Model& m, const State& s) {
  if (m.endless) return static_cast<long>(std::floor((s.front + s.line_offset) / m.endless_span));
  const auto it = std::upper_bound(m.support_x.begin(), m.support_x.end(), s.front);
  const long i = static_cast<long>(it - m.support_x.begin()) - 1;
  return std::clamp<long>(i, 0, static_cast<long>(m.support_x.size()) - 2);
}
}  // namespace

std::string heads_up_position(const Model& m, const State& s) {
  std::ostringstream head;
  head << std::fixed << std::setprecision(1) << "x " << s.front + s.line_offset << " m  span "
       << span_along_line(m, s) + 1 << "  t " << std::setprecision(2) << s.time << " s";
  return head.str();
}

void StripChart::clear(double window) {
  window_ = window;
  data_ = ChartData{};
  running_.clear();
  last_time_ = -1.0;
}

void StripChart::sample(const Model& m, const State& s) {
  if (s.time == last_time_) return;
  last_time_ = s.time;
  const std::size_t np = m.pantographs.size(), nw = m.contact_wires.size();
  if (data_.series.empty()) {
    running_.assign(np, Running{});
    for (std::size_t p = 0; p < np; ++p) {
      data_.series.push_back({m.pantographs[p].name, {}});
      if (nw > 1)
        for (std::size_t k = 0; k < nw; ++k)
          data_.series.push_back({m.pantographs[p].name + " on " + label_wire_name(m.wires[m.contact_wires[k]].name), {}});
    }
  }
  data_.time.push_back(s.time);
  std::size_t j = 0;
  for (std::size_t p = 0; p < np; ++p) {
    const double f = total_contact_force(m, s, static_cast<int>(p));
    data_.series[j++].force.push_back(f);
    Running& r = running_[p];
    r.n += 1;
    r.sum += f;
    r.sum2 += f * f;
    r.max = std::max(r.max, f);
    r.min = std::min(r.min, f);
    if (nw > 1)
      for (std::size_t k = 0; k < nw; ++k)
        data_.series[j++].force.push_back(s.pantograph_force_on(m, static_cast<int>(p), static_cast<int>(k)));
  }
  // Keep the window (and a sample before it, so the strip starts at the panel's edge).
  std::size_t drop = 0;
  while (drop + 1 < data_.time.size() && data_.time[drop + 1] < s.time - window_) ++drop;
  if (drop > 0) {
    data_.time.erase(data_.time.begin(), data_.time.begin() + drop);
    for (ChartSeries& c : data_.series) c.force.erase(c.force.begin(), c.force.begin() + drop);
  }
}

visualization_msgs::MarkerArray StripChart::markers(const Model& m, const std::string& heading,
                                                    const ros::Time& stamp) {
  data_.heading = heading;
  data_.stats.clear();
  for (std::size_t p = 0; p < running_.size(); ++p) {
    const Running& r = running_[p];
    if (r.n < 1) continue;
    const double mean = r.sum / r.n, sd = std::sqrt(std::max(0.0, r.sum2 / r.n - mean * mean));
    std::ostringstream t;
    t << std::fixed << std::setprecision(0) << m.pantographs[p].name << ": mean " << mean << ", std " << sd
      << ", max " << r.max << ", min " << r.min << " N (so far, unfiltered)";
    data_.stats.push_back(t.str());
  }
  ChartOptions co;
  co.window = window_;
  // The label has a third line with several contact wires (force on each) or on a 3-D line
  // (the contact point on the strip), one line higher: the panel goes up by as much as that
  // line spans seen from the default camera, so that the heads-up line stays clear of it.
  // It also moves left by as much, clear of the label's wider lines.
  if (m.contact_wires.size() > 1 || m.lateral) {
    co.z_bottom += kThirdLabelLineLift;
    co.origin_x -= kThirdLabelLineLift * co.dir_x;
    co.origin_y -= kThirdLabelLineLift * co.dir_y;
  }
  return to_strip_chart(data_, stamp, co);
}

}  // namespace ros_layer
}  // namespace catenary_sim
