// The loop's report (latency, jitter, overruns, counts) as JSON, for every transport's report file,
// and a one-line summary for the log. ROS-free.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "catenary_sim/core/output/statistics_json.hpp"
#include "catenary_sim/hil/loop.hpp"

namespace catenary_sim {
namespace hil {

// count, mean, p50, p90, p99, p99.9, max (s).
nlohmann::ordered_json histogram_json(const LatencyHistogram& h);
// rate, period, dt, counters, latency/compute/wait/transport percentiles and the loop's jitter
// (percentiles and a 10 us histogram).
nlohmann::ordered_json loop_report(const HilLoop& loop);
// "N periods in T s, N overruns, ...; latency p50 ... p99 ... max ...; jitter p99 ... max ..."
std::string loop_summary(const HilLoop& loop);

// The statistics file of a pass that ended (`state`: its last; `stats`: its recorder's), as
// simulate_pass writes stats.json: on a 3-D line with "stopped_by_dewirement". Empty, with `why`
// set, for a pass stopped at a dewirement before it gave statistics over the analysis section:
// simulate_pass writes nothing then either (no file of nulls).
std::string pass_stats_json(const Model& m, const State& state, const std::vector<PantographStatistics>& stats,
                            const RunInfo& run, std::string* why);

}  // namespace hil
}  // namespace catenary_sim
