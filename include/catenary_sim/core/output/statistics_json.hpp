// stats.json: the figures of a pass as the report (scripts/pass_report) and a study read them.
#pragma once

#include <string>
#include <vector>

#include "catenary_sim/core/engine/state.hpp"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/output/force_statistics.hpp"

namespace catenary_sim {

// How a pass ran, for the report (NaN / negative: left out).
struct RunInfo {
  double wall_time_s = 0.0;
  double build_time_s = -1.0;
  long long overruns = -1;
};

// The pass report as JSON (stats.json of simulate_pass, ~stats_file of the node): run figures and
// per pantograph the filtered and unfiltered force statistics.
// With `line`, also the droppers, the steady arms against output.allowed_uplift, the stations of
// supports and droppers and the scene's limits with pass/fail marks.
std::string statistics_json(const Model& model, const State& state, const std::vector<PantographStatistics>& stats,
                            const RunInfo& run, const LineStatistics* line = nullptr);

}  // namespace catenary_sim
