#include "catenary_sim/hil/report.hpp"

#include <cmath>
#include <cstdio>

namespace catenary_sim {
namespace hil {

namespace {
constexpr double kJitterBin = 10e-6;  // s, bins of the jitter histogram in the report
}

nlohmann::ordered_json histogram_json(const LatencyHistogram& h) {
  nlohmann::ordered_json j;  // (nlohmann writes a non-finite number as null)
  j["count"] = h.count();
  j["mean_s"] = h.mean();
  j["p50_s"] = h.quantile(0.5);
  j["p90_s"] = h.quantile(0.9);
  j["p99_s"] = h.quantile(0.99);
  j["p999_s"] = h.quantile(0.999);
  j["max_s"] = h.max();
  return j;
}

nlohmann::ordered_json loop_report(const HilLoop& L) {
  const LoopCounters& c = L.counters();
  const double wall = L.started() > 0.0 ? steady_now() - L.started() : 0.0;
  nlohmann::ordered_json j;
  j["rate_hz"] = L.options().rate;
  j["period_s"] = L.timing().period;
  j["dt_s"] = L.model().dt;
  j["steps_per_period"] = L.timing().steps_per_period;
  j["dofs"] = L.model().n_dof;
  j["wall_s"] = wall;
  j["sim_time_s"] = L.state().time;
  j["passes"] = L.pass_count() + 1;
  j["periods"] = c.batches;
  j["periods_triggered"] = c.triggered;
  j["periods_held"] = c.held;
  j["periods_safe_hold"] = c.hold_batches;
  j["safe_holds"] = c.holds;
  j["overruns"] = c.overruns;
  j["relocks"] = c.relocks;
  j["spin_wait_s"] = L.options().spin_wait;
  j["measurements_accepted"] = c.accepted;
  j["measurements_rejected"] = c.rejected;
  j["measurements_superseded"] = c.superseded;
  j["measurements_late"] = c.late;
  j["max_age_running_s"] = c.max_age_running;
  j["latency"] = histogram_json(L.latency());
  j["compute"] = histogram_json(L.compute());
  j["wait"] = histogram_json(L.wait());
  j["transport"] = histogram_json(L.transport());
  nlohmann::ordered_json jit = histogram_json(L.jitter());
  jit["bin_s"] = kJitterBin;
  jit["counts"] = L.jitter().coarse(kJitterBin);  // [i]: periods that started i x 10 us late
  j["jitter"] = jit;
  const CouplingEnergy& e = L.energy();
  nlohmann::ordered_json cq;
  cq["interface_energy_j"] = e.interface_j;
  cq["rig_energy_j"] = e.rig_j;
  cq["delay_energy_j"] = e.delay_j;
  cq["mean_interface_power_w"] = e.periods > 0 ? e.interface_j / (e.periods * L.timing().period) : 0.0;
  cq["peak_interface_power_w"] = e.peak_power_w;
  cq["periods"] = e.periods;
  cq["periods_answered_point_known"] = e.known;
  cq["delay_compensation_s"] = L.options().delay_compensation;
  j["coupling"] = cq;
  return j;
}

std::string loop_summary(const HilLoop& L) {
  const LoopCounters& c = L.counters();
  const double wall = L.started() > 0.0 ? steady_now() - L.started() : 0.0;
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "%lld periods in %.1f s, %lld overruns, %lld safe holds; latency (measurement arrival -> contact point "
                "sent) p50 %.1f us, p99 %.1f us, max %.1f us over %llu measurements; jitter (period start after its "
                "due time) p99 %.1f us, max %.1f us",
                static_cast<long long>(c.batches), wall, static_cast<long long>(c.overruns),
                static_cast<long long>(c.holds), L.latency().quantile(0.5) * 1e6, L.latency().quantile(0.99) * 1e6,
                L.latency().max() * 1e6, static_cast<unsigned long long>(L.latency().count()),
                L.jitter().quantile(0.99) * 1e6, L.jitter().max() * 1e6);
  return buf;
}

std::string pass_stats_json(const Model& m, const State& state, const std::vector<PantographStatistics>& stats,
                            const RunInfo& run, std::string* why) {
  const bool dewired = state.status == StepStatus::kDewired;
  if (dewired) {
    for (const PantographStatistics& s : stats)
      for (double v : {s.filtered.mean, s.filtered.std_dev, s.filtered.max, s.filtered.min, s.unfiltered.mean})
        if (!std::isfinite(v)) {
          if (why) *why = "the pass stopped at the dewirement before it crossed the analysis section; nothing written";
          return std::string();
        }
  }
  std::string text = statistics_json(m, state, stats, run);
  if (m.lateral) {
    nlohmann::ordered_json j = nlohmann::ordered_json::parse(text);
    j["stopped_by_dewirement"] = dewired;
    text = j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
  }
  return text;
}

}  // namespace hil
}  // namespace catenary_sim
