#include "catenary_sim/core/statistics.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace catenary_sim {
namespace {

struct Biquad {
  double b0, b1, b2, a1, a2;
};

// One pass of a biquad cascade (direct form II transposed), started in the steady state of the
// first sample so that the ends do not ring.
void run_cascade(const std::vector<Biquad>& cascade, std::vector<double>& x) {
  if (x.empty()) return;
  for (const Biquad& q : cascade) {
    const double x0 = x.front();
    double z2 = (q.b2 - q.a2) * x0;
    double z1 = (q.b1 - q.a1) * x0 + z2;
    for (double& xi : x) {
      const double in = xi;
      const double y = q.b0 * in + z1;
      z1 = q.b1 * in - q.a1 * y + z2;
      z2 = q.b2 * in - q.a2 * y;
      xi = y;
    }
  }
}

}  // namespace

std::vector<double> lowpass_zero_phase(const std::vector<double>& x, double fs, double fc) {
  const std::size_t n = x.size();
  if (n < 3 || fc >= 0.5 * fs) return x;
  // 4th-order Butterworth as two bilinear (pre-warped) sections with Q = 1/(2 cos(pi/8)) and
  // 1/(2 cos(3 pi/8)).
  std::vector<Biquad> cascade;
  const double w0 = 2.0 * M_PI * fc / fs, cw = std::cos(w0), sw = std::sin(w0);
  for (double q : {1.0 / (2.0 * std::cos(M_PI / 8.0)), 1.0 / (2.0 * std::cos(3.0 * M_PI / 8.0))}) {
    const double al = sw / (2.0 * q), a0 = 1.0 + al;
    cascade.push_back(Biquad{(1.0 - cw) / 2.0 / a0, (1.0 - cw) / a0, (1.0 - cw) / 2.0 / a0, -2.0 * cw / a0,
                             (1.0 - al) / a0});
  }
  // Odd reflection about each end over a few time constants of the filter.
  const std::size_t pad = std::min(n - 1, static_cast<std::size_t>(std::ceil(3.0 * fs / fc)));
  std::vector<double> y;
  y.reserve(n + 2 * pad);
  for (std::size_t i = pad; i >= 1; --i) y.push_back(2.0 * x.front() - x[i]);
  y.insert(y.end(), x.begin(), x.end());
  for (std::size_t i = 1; i <= pad; ++i) y.push_back(2.0 * x.back() - x[n - 1 - i]);
  run_cascade(cascade, y);
  std::reverse(y.begin(), y.end());
  run_cascade(cascade, y);
  std::reverse(y.begin(), y.end());
  return std::vector<double>(y.begin() + pad, y.begin() + pad + n);
}

ForceStatistics force_statistics(const std::vector<double>& x) {
  ForceStatistics s;
  if (x.empty()) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    s.mean = s.std_dev = s.max = s.min = s.stat_max = s.stat_min = nan;
    return s;
  }
  double sum = 0.0;
  s.max = -std::numeric_limits<double>::infinity();
  s.min = std::numeric_limits<double>::infinity();
  for (double v : x) {
    sum += v;
    s.max = std::max(s.max, v);
    s.min = std::min(s.min, v);
  }
  s.mean = sum / x.size();
  double var = 0.0;
  for (double v : x) var += (v - s.mean) * (v - s.mean);
  s.std_dev = std::sqrt(var / x.size());
  s.stat_max = s.mean + 3.0 * s.std_dev;
  s.stat_min = s.mean - 3.0 * s.std_dev;
  return s;
}

PassRecorder::PassRecorder(const Model& m, double sample_rate_hz)
    : sample_period_(sample_rate_hz > 0.0 ? 1.0 / sample_rate_hz : 0.0) {
  const std::size_t np = m.pantographs.size(), nw = m.contact_wires.size();
  position_.resize(np);
  force_.resize(np);
  wire_force_.assign(np, std::vector<std::vector<double>>(nw));
  for (std::size_t k = 0; k < m.springs.size(); ++k)
    if (m.springs[k].steady_arm) steady_arm_springs_.push_back(static_cast<int>(k));
  // In line order, so that record() looks only at the steady arms near each pantograph (its cost
  // per step must not grow with the line).
  std::stable_sort(steady_arm_springs_.begin(), steady_arm_springs_.end(),
                   [&](int a, int b) { return m.springs[a].x < m.springs[b].x; });
  for (int k : steady_arm_springs_) steady_arm_x_.push_back(m.springs[k].x);
  for (double l : m.scene.spans) longest_span_ = std::max(longest_span_, l);
  max_uplift_.resize(np);
  for (const Pantograph& p : m.pantographs) {
    columns_.push_back(p.name + "_position_m");
    for (std::size_t c = 0; c < p.collectors.size(); ++c)
      for (std::size_t w = 0; w < nw; ++w)
        columns_.push_back(p.name + "_collector" + std::to_string(c) +
                           (nw > 1 ? "_" + m.wires[m.contact_wires[w]].name : std::string()) + "_force_N");
    columns_.push_back(p.name + "_force_N");
    columns_.push_back(p.name + "_head_displacement_m");
  }
  // Per steady arm (not on an endless line, whose model moves along under the train).
  if (!m.endless)
    for (int k : steady_arm_springs_)
      columns_.push_back("uplift_steady_arm" + std::to_string(m.springs[k].span_index) + "_m");
}

void PassRecorder::record(const Model& m, const State& s) {
  const std::size_t np = m.pantographs.size(), nw = m.contact_wires.size();
  time_.push_back(s.time);
  for (std::size_t p = 0; p < np; ++p) {
    const double xp = s.front - m.pantographs[p].position;  // model station
    position_[p].push_back(xp + s.line_offset);
    force_[p].push_back(total_contact_force(m, s, static_cast<int>(p)));
    for (std::size_t w = 0; w < nw; ++w) {
      double f = 0.0;
      for (int ci : m.pantographs[p].collectors) f += s.contact_force[ci * nw + w];
      wire_force_[p][w].push_back(f);
    }
    const auto first = std::lower_bound(steady_arm_x_.begin(), steady_arm_x_.end(), xp - longest_span_);
    for (std::size_t k = first - steady_arm_x_.begin(); k < steady_arm_x_.size() && steady_arm_x_[k] <= xp + longest_span_; ++k) {
      const SupportSpring& sp = m.springs[steady_arm_springs_[k]];
      const int span = sp.span_index;
      const double reach = 0.5 * std::min(m.scene.spans[span - 1], m.scene.spans[span]);
      if (std::fabs(xp - sp.x) > reach) continue;
      // Keyed by the steady arm's station along the line (mm), which on an endless line is not
      // the same spring from one span to the next.
      const long long key = std::llround(1e3 * (sp.x + s.line_offset));
      const auto it = max_uplift_[p].find(key);
      if (it == max_uplift_[p].end()) max_uplift_[p].emplace(key, s.u[sp.dof]);
      else it->second = std::max(it->second, s.u[sp.dof]);
    }
  }
  if (sample_period_ > 0.0 && s.time + 1e-12 < next_sample_) return;
  next_sample_ += sample_period_;
  Row row{s.time, {}};
  row.values.reserve(columns_.size());
  for (std::size_t p = 0; p < np; ++p) {
    const Pantograph& pg = m.pantographs[p];
    row.values.push_back(position_[p].back() + 0.0);  // + 0.0: no "-0" in the CSV
    for (int ci : pg.collectors)
      for (std::size_t w = 0; w < nw; ++w) row.values.push_back(s.contact_force[ci * nw + w]);
    row.values.push_back(force_[p].back());
    row.values.push_back(pg.moving_force ? 0.0 : s.u[pg.first_dof]);
  }
  if (!m.endless)
    for (int k : steady_arm_springs_) row.values.push_back(s.u[m.springs[k].dof]);
  rows_.push_back(std::move(row));
}

std::vector<PantographStatistics> PassRecorder::statistics(const Model& m) const {
  return statistics(m, m.scene.output.filter_cutoff);
}

std::vector<PantographStatistics> PassRecorder::statistics(const Model& m, double cutoff_hz) const {
  std::vector<PantographStatistics> out;
  double x0 = 0.0, x1 = 0.0;
  analysis_section(m, &x0, &x1);
  const double fs = 1.0 / m.dt;
  for (std::size_t p = 0; p < m.pantographs.size(); ++p) {
    PantographStatistics st;
    st.name = m.pantographs[p].name;
    const std::vector<double> filtered = lowpass_zero_phase(force_[p], fs, cutoff_hz);
    std::vector<double> f_in, raw_in;
    std::size_t lost = 0;
    for (std::size_t i = 0; i < force_[p].size(); ++i) {
      const double x = position_[p][i];
      if (x < x0 || x > x1) continue;
      f_in.push_back(filtered[i]);
      raw_in.push_back(force_[p][i]);
      lost += force_[p][i] <= 0.0;
    }
    st.samples = raw_in.size();
    st.filtered = force_statistics(f_in);
    st.unfiltered = force_statistics(raw_in);
    st.contact_loss_percent = raw_in.empty() ? std::nan("") : 100.0 * lost / raw_in.size();
    double up = -std::numeric_limits<double>::infinity();
    for (const auto& [key, uplift] : max_uplift_[p]) {
      const double xs = 1e-3 * key;
      if (xs >= x0 - 1e-6 && xs <= x1 + 1e-6) up = std::max(up, uplift);
    }
    st.max_uplift_at_support_m = std::isfinite(up) ? up : std::nan("");
    for (std::size_t w = 0; w < m.contact_wires.size(); ++w) {
      WireContactStatistics ws;
      ws.wire = m.wires[m.contact_wires[w]].name;
      double sum = 0.0;
      std::size_t n = 0, on = 0;
      for (std::size_t i = 0; i < force_[p].size(); ++i) {
        if (position_[p][i] < x0 || position_[p][i] > x1) continue;
        const double f = wire_force_[p][w][i];
        sum += f;
        ws.max_force = std::max(ws.max_force, f);
        on += f > 0.0;
        ++n;
      }
      ws.mean_force = n ? sum / n : std::nan("");
      ws.contact_percent = n ? 100.0 * on / n : std::nan("");
      st.wires.push_back(ws);
    }
    out.push_back(st);
  }
  return out;
}

namespace {

using Json = nlohmann::ordered_json;  // keeps the fields in the order a reader expects

// NaN and inf become null (what nlohmann writes for non-finite numbers): "no value", e.g. no
// steady arm in the section.
Json force_json(const ForceStatistics& f) {
  return Json{{"mean_force_N", f.mean},         {"std_force_N", f.std_dev},
              {"max_force_N", f.max},           {"min_force_N", f.min},
              {"stat_max_force_N", f.stat_max}, {"stat_min_force_N", f.stat_min}};
}

}  // namespace

std::string statistics_json(const Model& m, const State& s, const std::vector<PantographStatistics>& stats,
                            const RunInfo& run) {
  const Scene& scene = m.scene;
  Json j;
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
  Json pantographs = Json::array();
  for (const PantographStatistics& p : stats) {
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
    pantographs.push_back(pj);
  }
  j["pantographs"] = pantographs;
  // Replace invalid UTF-8 in names rather than throw: a scene name is the user's text.
  return j.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

}  // namespace catenary_sim
