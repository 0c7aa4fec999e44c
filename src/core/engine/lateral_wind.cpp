// The lateral plane's wind from the turbulent field (wind_field.hpp), per node normal to its wire.
#include "engine/lateral_wind.hpp"

#include <algorithm>
#include <cmath>

#include "engine/lateral_window.hpp"

namespace catenary_sim {

const WindFieldBuffer& field_values(const Model& m, const State& s) {
  return m.endless ? s.lateral.wind_field : m.lateral->field_values;
}

void extend_endless_field(const Model& m, State& s, double offset) {
  const WindField& fd = m.lateral->field;
  s.lateral.wind_field.extend_to(fd, static_cast<int>(std::floor((m.lateral->field_block_end + offset - fd.x0) / fd.dx)) + 1);
}

void refresh_wind(const Model& m, State& s, int i0, int i1) {
  wind_on_nodes(m, s, s.lateral.wind_points.data(), i0, i1, s.lateral.wind_speed.data());
}

void wind_on_nodes(const Model& m, const State& s, const double* wp, int i0, int i1, double* W) {
  const LateralModel& lat = *m.lateral;
  const double U = lat.wind_speed;
  const double* sn = lat.wind_normal.data();
  if (m.endless) {
    // The block's nodes at their stations along the line now, from the points held from `first`
    // (which cover the block: extend_endless_field).
    const WindField& fd = lat.field;
    const int first = s.lateral.wind_field.first(), top = std::max(first, s.lateral.wind_field.end() - 2);
    for (int i = i0; i < i1; ++i) {
      int j = 0;
      double a = 0.0;
      fd.locate(lat.node_x[i] + s.line_offset, &j, &a);
      j = std::clamp(j, first, top) - first;
      W[i] = (U + (1.0 - a) * wp[j] + a * wp[j + 1]) * sn[i];
    }
  } else {
    // Per run of nodes between two field points (the same operations as per node).
    const std::vector<LateralModel::FieldRun>& runs = lat.field_runs;
    std::size_t k = std::upper_bound(runs.begin(), runs.end(), i0,
                                     [](int i, const LateralModel::FieldRun& r) { return i < r.begin; }) -
                    runs.begin();
    k = k > 0 ? k - 1 : 0;
    const double* weight = lat.field_weight.data();
    for (; k < runs.size() && runs[k].begin < i1; ++k) {
      const double p0 = wp[runs[k].point], p1 = wp[runs[k].point + 1];
      const int b = std::max(i0, runs[k].begin), e = std::min(i1, runs[k].end);
      for (int i = b; i < e; ++i) {
        const double a = weight[i];
        W[i] = (U + (1.0 - a) * p0 + a * p1) * sn[i];
      }
    }
  }
}

void refresh_wind_if_due(const Model& m, State& s, double t, bool windowed) {
  const LateralModel& lat = *m.lateral;
  LateralState& ls = s.lateral;
  if (!lat.windy || lat.field.empty() || !(t + 1e-12 >= ls.next_wind_update)) return;
  ls.next_wind_update = t + kWindRefreshShare * lat.field.dt;
  ls.wind_time = t;
  if (m.endless) extend_endless_field(m, s, s.line_offset);
  field_values(m, s).at_time(lat.field, t, ls.wind_points.data());
  over_stepped(m, s, windowed, [&](int i0, int i1) { refresh_wind(m, s, i0, i1); });  // (only where stepped)
}

}  // namespace catenary_sim
