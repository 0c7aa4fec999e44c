#include "catenary_sim/core/output/statistics_json.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <optional>

namespace catenary_sim {
namespace {

using Json = nlohmann::ordered_json;  // keeps the fields in the order a reader expects

// NaN and inf become null (what nlohmann writes for non-finite numbers): "no value", e.g. no
// steady arm in the section.
Json force_json(const ForceStatistics& f) {
  return Json{{"mean_force_N", f.mean},         {"std_force_N", f.std_dev},
              {"max_force_N", f.max},           {"min_force_N", f.min},
              {"stat_max_force_N", f.stat_max}, {"stat_min_force_N", f.stat_min}};
}

// The scene's figures and how the pass ran.
void put_run(Json& j, const Model& m, const State& s, const RunInfo& run) {
  const Scene& scene = m.scene;
  j["scene"] = scene.name;
  j["speed_kmh"] = s.speed * 3.6;
  j["dofs"] = m.n_dof;
  j["dt_s"] = m.dt;
  j["dt_critical_s"] = m.dt_critical;
  j["steps"] = s.steps;
  j["simulated_time_s"] = s.time;
  if (run.build_time_s >= 0.0) j["build_time_s"] = run.build_time_s;
  j["wall_time_s"] = run.wall_time_s;
  j["real_time_factor"] = run.wall_time_s > 0.0 ? s.time / run.wall_time_s : std::nan("");
  if (run.overruns >= 0) j["overruns"] = run.overruns;
  double x0 = 0.0, x1 = 0.0;
  analysis_section(m, &x0, &x1);
  j["analysis_section_m"] = {x0, x1};
  j["filter_cutoff_hz"] = scene.output.filter_cutoff;
  if (m.sections.size() > 1) {
    // The transition supports' rise d (eq. 8, or overlap.support_rise): what an overlap study varies.
    Json rises = Json::array();
    for (const Section& sec : m.sections) rises.push_back({{"first_m", sec.rise_first}, {"last_m", sec.rise_last}});
    j["section_support_rises"] = rises;
  }
}

Json loss_events_json(const PantographStatistics& p) {
  Json losses;
  losses["count"] = p.loss_events_total;
  losses["per_km"] = p.loss_events_per_km;
  losses["longest_s"] = p.longest_loss_s;
  Json events = Json::array();
  constexpr std::size_t kMaxEvents = 1000;  // all of them in contact_losses.csv
  for (std::size_t i = 0; i < p.loss_events.size() && i < kMaxEvents; ++i) {
    const ContactLossEvent& e = p.loss_events[i];
    events.push_back(Json{{"start_time_s", e.start_time}, {"station_m", e.station}, {"duration_s", e.duration},
                          {"length_m", e.length}});
  }
  losses["events"] = events;
  losses["events_truncated"] = p.loss_events_total > events.size();
  return losses;
}

Json spectrum_json(const SpectrumSummary& s) {
  Json sp;
  sp["span_passing_hz"] = s.span_passing_hz;
  sp["dropper_passing_hz"] = s.dropper_passing_hz;
  sp["resolution_hz"] = s.resolution_hz;
  sp["segment_s"] = s.segment_s;
  sp["segments"] = s.segments;
  Json peaks = Json::array();
  for (const SpectralPeak& k : s.peaks)
    peaks.push_back(Json{{"frequency_hz", k.frequency}, {"psd_N2_per_hz", k.psd}, {"amplitude_N", k.amplitude}});
  sp["peaks"] = peaks;
  return sp;
}

Json target_mean_json(const PantographStatistics& p, const Scene& scene) {
  if (!p.target_mean) return nullptr;
  const PantographStatistics::TargetMean& t = *p.target_mean;
  const TargetMeanForce* spec = nullptr;
  for (const PantographSpec& ps : scene.pantographs)
    if (ps.name == p.name && ps.target_mean_force) spec = &*ps.target_mean_force;
  Json tj{{"speed_kmh", 3.6 * t.speed_mps}, {"target_N", t.target}, {"mean_N", p.filtered.mean},
          {"difference_N", t.difference}, {"tolerance_N", t.tolerance ? Json(*t.tolerance) : Json(nullptr)},
          {"within", t.within}};
  if (spec) tj["curve"] = Json{{"a", spec->a}, {"b", spec->b}, {"speed_unit", spec->speed_kmh ? "km/h" : "m/s"}};
  return tj;
}

Json pantograph_json(const PantographStatistics& p, const Scene& scene) {
  Json pj;
  pj["name"] = p.name;
  pj["samples"] = p.samples;
  pj.update(force_json(p.filtered));
  pj["contact_loss_percent"] = p.contact_loss_percent;
  pj["max_uplift_at_support_m"] = p.max_uplift_at_support_m;
  pj["unfiltered"] = force_json(p.unfiltered);
  Json wires = Json::array();
  for (const WireContactStatistics& w : p.wires)
    wires.push_back(Json{{"wire", w.wire}, {"mean_force_N", w.mean_force}, {"max_force_N", w.max_force},
                         {"contact_percent", w.contact_percent}});
  pj["contact_wires"] = wires;
  pj["contact_loss_events"] = loss_events_json(p);
  pj["spectrum"] = spectrum_json(p.spectrum);
  pj["target_mean_force"] = target_mean_json(p, scene);
  if (p.measured.available) {
    Json me;
    me["sensor_bandwidth_hz"] = p.measured.bandwidth_hz;
    me.update(force_json(p.measured.force));
    me["rms_difference_N"] = p.measured.rms_difference;
    me["max_abs_difference_N"] = p.measured.max_abs_difference;
    pj["measured"] = me;
  } else {
    pj["measured"] = nullptr;
  }
  return pj;
}

// The scene's limits, each against the worst pantograph.
Json limits_json(const OutputSpec& o, const std::vector<PantographStatistics>& stats, const LineStatistics& line) {
  Json limits = Json::array();
  auto mark = [&](const char* name, const std::optional<double>& limit, bool upper, double value) {
    if (!limit) return;
    limits.push_back(Json{{"name", name}, {"limit", *limit}, {"kind", upper ? "max" : "min"}, {"value", value},
                          {"pass", std::isfinite(value) && (upper ? value <= *limit : value >= *limit)}});
  };
  double stat_max = -INFINITY, stat_min = INFINITY, loss = -INFINITY, uplift = -INFINITY;
  for (const PantographStatistics& p : stats) {
    stat_max = std::max(stat_max, p.filtered.stat_max);
    stat_min = std::min(stat_min, p.filtered.stat_min);
    loss = std::max(loss, p.contact_loss_percent);
  }
  for (const SteadyArmStatistics& a : line.steady_arms) uplift = std::max(uplift, a.max_uplift);
  // (the same value on a finite line; an endless one lists only its last arms)
  for (const PantographStatistics& p : stats) uplift = std::max(uplift, p.max_uplift_at_support_m);
  mark("stat_max_force_N", o.max_stat_force, true, stat_max);
  mark("stat_min_force_N", o.min_stat_force, false, stat_min);
  mark("contact_loss_percent", o.max_contact_loss_percent, true, loss);
  mark("max_uplift_m", o.allowed_uplift, true, uplift);
  return limits;
}

// The line's figures: steady arms, droppers, the stations of both and the scene's limits.
void put_line(Json& j, const Model& m, const std::vector<PantographStatistics>& stats, const LineStatistics& line) {
  const OutputSpec& o = m.scene.output;
  auto opt = [](const std::optional<double>& v) { return v ? Json(*v) : Json(nullptr); };
  j["allowed_uplift_m"] = opt(o.allowed_uplift);
  Json arms = Json::array();
  for (const SteadyArmStatistics& a : line.steady_arms) {
    Json arm{{"station_m", a.station}, {"max_uplift_m", a.max_uplift}, {"exceeded", a.exceeded}};
    if (a.hinged) {
      arm["stiffness_N_per_m"] = a.stiffness;
      arm["pull_off_N"] = a.pull_off;
      arm["inclination_rad"] = a.inclination;
      arm["inclination_at_max_uplift_rad"] = a.inclination_at_max_uplift;
      arm["registration_travel_m"] = a.registration_travel;
    }
    arms.push_back(arm);
  }
  j["steady_arms"] = arms;
  Json dr;
  dr["rainflow_bin_N"] = line.range_bin_n;
  Json list = Json::array();
  for (const DropperStatistics& d : line.droppers) {
    list.push_back(Json{{"station_m", d.station},       {"static_tension_N", d.static_tension},
                        {"max_force_N", d.max_force},   {"min_force_N", d.min_force},
                        {"slack_percent", d.slack_percent}, {"rainflow_cycles", d.cycles},
                        {"max_range_N", d.max_range}});
    if (d.hanger) list.back()["hanger"] = true;  // a compound line's: auxiliary messenger to contact wire
  }
  dr["list"] = list;
  j["droppers"] = dr;
  Json supports = Json::array();
  for (double x : m.support_x) supports.push_back(x);
  j["support_stations_m"] = supports;
  Json dst = Json::array();
  for (int k : m.dropper_order) dst.push_back(m.droppers[k].x);
  j["dropper_stations_m"] = dst;
  j["limits"] = limits_json(o, stats, line);
}

}  // namespace

std::string statistics_json(const Model& m, const State& s, const std::vector<PantographStatistics>& stats,
                            const RunInfo& run, const LineStatistics* line) {
  Json j;
  put_run(j, m, s, run);
  Json pantographs = Json::array();
  for (const PantographStatistics& p : stats) pantographs.push_back(pantograph_json(p, m.scene));
  j["pantographs"] = pantographs;
  if (line) put_line(j, m, stats, *line);
  // Replace invalid UTF-8 in names rather than throw: a scene name is the user's text.
  return j.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

}  // namespace catenary_sim
