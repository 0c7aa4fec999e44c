// Where the line's parts are now, as both the messages (conversions.cpp) and the rviz markers
// (markers.cpp) read them: the sampled nodes of a wire, lateral positions on a 3-D line, a
// collector's station. Private to the ROS layer.
#pragma once

#include <cstddef>
#include <vector>

#include "catenary_sim/core/engine/state.hpp"
#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {
namespace ros_layer {

// Node indices of a wire sampled at about `resolution` m; its first and last nodes (a clamp, an
// anchor) and its support nodes (where a steady arm, a bracket or a bridle's middle holds it)
// always included, so that what holds the wire is drawn on it at any resolution.
inline std::vector<int> sample_nodes(const Wire& w, double resolution) {
  std::vector<int> idx;
  const int n = w.nodes();
  if (n == 0) return idx;
  idx.push_back(0);
  double last = w.x[0];
  std::size_t next_support = 0;  // (support_nodes ascending)
  for (int i = 1; i + 1 < n; ++i) {
    while (next_support < w.support_nodes.size() && w.support_nodes[next_support] < i) ++next_support;
    const bool support = next_support < w.support_nodes.size() && w.support_nodes[next_support] == i;
    if (support || w.x[i] - last + 1e-9 >= resolution) {
      idx.push_back(i);
      last = w.x[i];
    }
  }
  if (n > 1) idx.push_back(n - 1);
  return idx;
}

// Lateral position (m, + left of the track centre line) of node i of wire wi now; 0 on a 2-D line.
inline double node_lateral(const Model& m, const State& s, std::size_t wi, int i) {
  if (!m.lateral || s.lateral.y.size() != m.lateral->n) return 0.0;
  return lateral_position(m, s, m.lateral->wires[wi].w_dof + i);
}

// The pantograph head's centre across the track (sway); 0 on a 2-D line.
inline double head_lateral(const Model& m, const State& s, std::size_t p) {
  return m.lateral && p < s.lateral.pantograph_lateral.size() ? s.lateral.pantograph_lateral[p] : 0.0;
}

// Station of a collector of pantograph p now, in the model's stations (the wires' x; on an
// endless line the line's station is this plus State::line_offset).
inline double collector_x(const Model& m, const State& s, int p, int ci) {
  return s.front - m.pantographs[p].position + m.collectors[ci].offset;
}

}  // namespace ros_layer
}  // namespace catenary_sim
