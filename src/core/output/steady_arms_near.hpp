// The steady arms a pantograph passes (the whole-record and the endless recorders alike): the
// uplift at a steady arm counts while a pantograph is within half a span of it, the shorter of its
// two spans, so that each arm takes the uplift of its own passage.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

// Calls visit(spring, station_mm) for every steady arm within reach of the pantograph at model
// station xp: `arms` indexes Model::springs in line order, `arm_x` holds their stations and
// `longest_span` bounds the search. station_mm keys the arm by its station along the line
// (model station + line_offset, mm), which on an endless line is not the same spring from one
// span to the next.
template <class Visit>
void for_each_steady_arm_near(const Model& m, const std::vector<int>& arms, const std::vector<double>& arm_x,
                              double longest_span, double line_offset, double xp, Visit&& visit) {
  const auto first = std::lower_bound(arm_x.begin(), arm_x.end(), xp - longest_span);
  for (std::size_t k = first - arm_x.begin(); k < arm_x.size() && arm_x[k] <= xp + longest_span; ++k) {
    const SupportSpring& sp = m.springs[arms[k]];
    const int span = sp.span_index;
    const double reach = 0.5 * std::min(m.scene.spans[span - 1], m.scene.spans[span]);
    if (std::fabs(xp - sp.x) > reach) continue;
    visit(sp, std::llround(1e3 * (sp.x + line_offset)));
  }
}

}  // namespace catenary_sim
