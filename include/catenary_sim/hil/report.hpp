// The loop's report (latency, jitter, overruns, counts) as JSON, for every transport's report file,
// and a one-line summary for the log. ROS-free.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

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

}  // namespace hil
}  // namespace catenary_sim
