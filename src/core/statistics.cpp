#include "catenary_sim/core/statistics.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
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

PassRecorder::PassRecorder(const Model& m, double sample_rate_hz) : PassRecorder(m, sample_rate_hz, true) {}

PassRecorder::PassRecorder(const Model& m, double sample_rate_hz, bool record_droppers)
    : sample_period_(sample_rate_hz > 0.0 ? 1.0 / sample_rate_hz : 0.0) {
  const std::size_t np = m.pantographs.size(), nw = m.contact_wires.size();
  position_.resize(np);
  force_.resize(np);
  head_u_.resize(np);
  suspension_stretch_.resize(np);
  suspension_force_.resize(np);
  // The droppers of the analysis section (the model's droppers are fixed to the line except on an
  // endless line, whose block moves under the train: none there).
  if (record_droppers && !m.endless) {
    double x0 = 0.0, x1 = 0.0;
    analysis_section(m, &x0, &x1);
    for (int k : m.dropper_order) {
      const double x = m.droppers[k].x;
      if (x < x0 || x > x1) continue;
      DropperTrack t;
      t.index = k;
      t.station = x;
      droppers_.push_back(t);
    }
  }
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
    names_.push_back(p.name);
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

namespace {

// A dropper's force as the explicit integrator decides it: elastic tension, nothing when slack.
// On a 3-D line the stretch has the lean's share (LateralState::dropper_stretch, lateral.hpp):
// a leaning dropper is a stiff link along itself, so the vertical plane gives way to a change of
// lean by about as much (u_m - u_c ~ -lean), and the vertical stretch alone would read k times
// the lean's change (60 N per 0.3 mm) as force or slack the dropper does not have.
inline double dropper_force(const Model& m, std::size_t k, const State& s, bool* slack) {
  const Dropper& d = m.droppers[k];
  double stretch = s.u[d.messenger_dof] - s.u[d.contact_dof];
  if (m.lateral && !s.lateral.dropper_stretch.empty()) stretch += s.lateral.dropper_stretch[k];
  const double t = d.static_tension + d.stiffness * stretch;
  *slack = !(t > 0.0);
  return *slack ? 0.0 : t;
}

// Mean train speed over the samples in the section (m/s).
double section_speed(const std::vector<double>& t, const std::vector<double>& x, double x0, double x1) {
  std::size_t first = t.size(), last = 0;
  for (std::size_t i = 0; i < t.size(); ++i)
    if (x[i] >= x0 && x[i] <= x1) {
      first = std::min(first, i);
      last = i;
    }
  if (first >= last || !(t[last] > t[first])) return std::nan("");
  return (x[last] - x[first]) / (t[last] - t[first]);
}

}  // namespace

void PassRecorder::record(const Model& m, const State& s) {
  const std::size_t np = m.pantographs.size(), nw = m.contact_wires.size();
  time_.push_back(s.time);
  ++steps_;
  for (DropperTrack& t : droppers_) {
    bool slack = false;
    const double f = dropper_force(m, t.index, s, &slack);
    t.max = std::max(t.max, f);
    t.min = std::min(t.min, f);
    t.slack += slack;
    t.reversals.add(f);
  }
  for (std::size_t p = 0; p < np; ++p) {
    const Pantograph& pg = m.pantographs[p];
    if (!pg.moving_force) {
      // Head suspension: the spring (and damper) from the head to the mass below (the roof for a
      // one-mass pantograph, whose uplift then acts on the head too).
      const int a0 = pg.first_dof, nm = pg.masses_count();
      if (pg.heads.empty()) {
        const double stretch = (nm > 1 ? s.u[a0 + 1] : 0.0) - s.u[a0];
        double fe = pg.spring_preload[0] + pg.stiffness[0] * stretch;
        if (nm == 1) fe += s.uplift[p] + pg.aero_coefficient * air_speed_squared(s, p);
        head_u_[p].push_back(s.u[a0]);
        suspension_stretch_[p].push_back(stretch);
        suspension_force_[p].push_back(fe);
      } else {
        // Every head's own suspension to the top frame mass (and its own aero force, which acts
        // on the head), one entry per head per step: the load cells sit under each head.
        for (const Head& h : pg.heads) {
          const double stretch = s.u[a0] - s.u[h.dof];
          head_u_[p].push_back(s.u[h.dof]);
          suspension_stretch_[p].push_back(stretch);
          suspension_force_[p].push_back(h.preload + h.stiffness * stretch + h.aero_coefficient * air_speed_squared(s, p));
        }
      }
    }
    const double xp = s.front - pg.position;  // model station
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
  // The samples run from the first recorded state: a recorder started after a reset that kept the
  // clock running samples at its rate from there, not every step until it reaches the clock.
  if (rows_.empty()) next_sample_ = s.time;
  if (sample_period_ > 0.0 && s.time + 1e-12 < next_sample_) return;
  next_sample_ += sample_period_;
  row_index_.push_back(time_.size() - 1);
  if (m.scene.output.dropper_series && !droppers_.empty()) {
    Row dr{s.time, {}};
    dr.values.reserve(droppers_.size());
    bool slack = false;
    for (const DropperTrack& t : droppers_) dr.values.push_back(dropper_force(m, t.index, s, &slack));
    dropper_rows_.push_back(std::move(dr));
  }
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
    st.loss_events = contact_loss_events(time_, position_[p], force_[p], x0, x1);
    st.loss_events_per_km = x1 > x0 ? st.loss_events.size() / ((x1 - x0) / 1000.0) : std::nan("");
    st.longest_loss_s = 0.0;
    for (const ContactLossEvent& e : st.loss_events) st.longest_loss_s = std::max(st.longest_loss_s, e.duration);
    st.spectrum = spectrum_summary(m, p, spectrum(m, p));
    measured_statistics(m, p, x0, x1, filtered, &st.measured);
    const std::optional<TargetMeanForce>& target = m.scene.pantographs[p].target_mean_force;
    const double v = section_speed(time_, position_[p], x0, x1);
    if (target && std::isfinite(v) && std::isfinite(st.filtered.mean)) {
      // The standards' permissible mean force against the pass's (filtered) mean, at the mean speed.
      PantographStatistics::TargetMean t;
      t.speed_mps = v;
      t.target = target->at(v);
      t.difference = st.filtered.mean - t.target;
      t.tolerance = target->tolerance;
      t.within = !t.tolerance || std::fabs(t.difference) <= *t.tolerance;
      st.target_mean = t;
    }
    out.push_back(st);
  }
  return out;
}

std::vector<double> PassRecorder::measured_force(const Model& m, std::size_t p) const {
  const Pantograph& pg = m.pantographs[p];
  const std::vector<double>& u = head_u_[p];
  const std::vector<double>& d = suspension_stretch_[p];
  const std::vector<double>& fe = suspension_force_[p];
  if (pg.moving_force) return {};
  const std::size_t heads = pg.heads.empty() ? 1 : pg.heads.size(), n = u.size() / heads;
  if (n < 3) return {};
  // Head: m a = F_suspension - F_contact, so F_contact = F_suspension - m a, with the damper's
  // velocity and the head's acceleration by central differences of the recorded displacements
  // (as an accelerometer and load cells would give them, at every step); summed over the heads.
  const double dt = m.dt;
  std::vector<double> f(n, 0.0);
  for (std::size_t h = 0; h < heads; ++h) {
    const double mass = pg.heads.empty() ? pg.masses[0] : pg.heads[h].mass;
    const double c = pg.heads.empty() ? pg.damping[0] : pg.heads[h].damping;
    for (std::size_t i = 1; i + 1 < n; ++i) {
      const std::size_t j = i * heads + h, jp = j + heads, jm = j - heads;
      const double vel = (d[jp] - d[jm]) / (2.0 * dt);
      const double acc = (u[jp] - 2.0 * u[j] + u[jm]) / (dt * dt);
      f[i] += fe[j] + c * vel - mass * acc;
    }
  }
  f[0] = f[1];
  f[n - 1] = f[n - 2];
  return lowpass_zero_phase(f, 1.0 / dt, m.scene.output.sensor_bandwidth);
}

void PassRecorder::measured_statistics(const Model& m, std::size_t p, double x0, double x1,
                                       const std::vector<double>& filtered, MeasuredForceStatistics* out) const {
  *out = MeasuredForceStatistics{};
  out->bandwidth_hz = m.scene.output.sensor_bandwidth;
  const std::vector<double> meas = measured_force(m, p);
  if (meas.size() != force_[p].size()) return;
  std::vector<double> in;
  double sq = 0.0, worst = 0.0;
  for (std::size_t i = 0; i < meas.size(); ++i) {
    const double x = position_[p][i];
    if (x < x0 || x > x1) continue;
    in.push_back(meas[i]);
    const double diff = meas[i] - filtered[i];
    sq += diff * diff;
    worst = std::max(worst, std::fabs(diff));
  }
  if (in.empty()) return;
  out->available = true;
  out->force = force_statistics(in);
  out->rms_difference = std::sqrt(sq / in.size());
  out->max_abs_difference = worst;
}

namespace {

// Mean span length over [x0, x1] (supports of all sections, duplicates of overlaps once).
double mean_span(const Model& m, double x0, double x1) {
  if (m.endless) return m.endless_span;
  std::vector<double> xs;
  for (double x : m.support_x)
    if (x >= x0 - 1e-6 && x <= x1 + 1e-6) xs.push_back(x);
  std::sort(xs.begin(), xs.end());
  xs.erase(std::unique(xs.begin(), xs.end(), [](double a, double b) { return std::fabs(a - b) < 1e-6; }), xs.end());
  if (xs.size() < 2) return m.longest_span;
  return (xs.back() - xs.front()) / (xs.size() - 1);
}

// Median spacing of consecutive droppers within a span over [x0, x1]; NaN without droppers.
double dropper_spacing(const Model& m, double x0, double x1) {
  std::vector<double> gaps;
  const Dropper* last = nullptr;
  for (int k : m.dropper_order) {
    const Dropper& d = m.droppers[k];
    if (d.x < x0 || d.x > x1) continue;
    if (last && last->section == d.section && last->span == d.span && d.x - last->x > 1e-6) gaps.push_back(d.x - last->x);
    last = &d;
  }
  if (gaps.empty()) return std::nan("");
  std::sort(gaps.begin(), gaps.end());
  return gaps[gaps.size() / 2];
}


}  // namespace

Spectrum PassRecorder::spectrum(const Model& m, std::size_t p) const {
  double x0 = 0.0, x1 = 0.0;
  analysis_section(m, &x0, &x1);
  std::vector<double> in;
  for (std::size_t i = 0; i < force_[p].size(); ++i)
    if (position_[p][i] >= x0 && position_[p][i] <= x1) in.push_back(force_[p][i]);
  const double fs = 1.0 / m.dt;
  // Segments of 8 span-passing periods (a resolution of 1/8 of the span-passing frequency), or the
  // whole section when it is shorter.
  const double v = section_speed(time_, position_[p], x0, x1);
  std::size_t seg = in.size();
  if (v > 0.0) seg = std::min(seg, static_cast<std::size_t>(std::ceil(8.0 * mean_span(m, x0, x1) / v * fs)));
  return welch_psd(in, fs, seg);
}

std::vector<Spectrum> PassRecorder::spectra(const Model& m) const {
  std::vector<Spectrum> out;
  for (std::size_t p = 0; p < m.pantographs.size(); ++p) out.push_back(spectrum(m, p));
  return out;
}

SpectrumSummary PassRecorder::spectrum_summary(const Model& m, std::size_t p, const Spectrum& sp) const {
  double x0 = 0.0, x1 = 0.0;
  analysis_section(m, &x0, &x1);
  SpectrumSummary s;
  const double v = section_speed(time_, position_[p], x0, x1);
  s.span_passing_hz = v / mean_span(m, x0, x1);
  s.dropper_passing_hz = v / dropper_spacing(m, x0, x1);
  s.resolution_hz = sp.resolution;
  s.segment_s = sp.segment * m.dt;
  s.segments = sp.segments;
  s.peaks = spectral_peaks(sp, 2.0 * sp.resolution, kSpectrumMaxHz, 5);
  return s;
}

LineStatistics PassRecorder::line_statistics(const Model& m) const {
  LineStatistics ls;
  constexpr int kBins = 20;
  std::vector<std::vector<RainflowCycle>> cycles;
  double top = 0.0;
  for (const DropperTrack& t : droppers_) {
    const Dropper& d = m.droppers[t.index];
    DropperStatistics ds;
    ds.station = d.x;
    ds.span = d.section * 1000 + d.span;
    ds.static_tension = d.static_tension;
    ds.max_force = steps_ ? t.max : std::nan("");
    ds.min_force = steps_ ? t.min : std::nan("");
    ds.slack_percent = steps_ ? 100.0 * t.slack / steps_ : std::nan("");
    cycles.push_back(rainflow(t.reversals.points()));
    for (const RainflowCycle& c : cycles.back()) {
      ds.cycles += c.count;
      ds.max_range = std::max(ds.max_range, c.range);
    }
    top = std::max(top, ds.max_range);
    ls.droppers.push_back(ds);
  }
  ls.range_bin_n = top > 0.0 ? top / kBins : 1.0;
  for (std::size_t k = 0; k < ls.droppers.size(); ++k)
    ls.droppers[k].histogram = rainflow_histogram(cycles[k], ls.range_bin_n * kBins, kBins);
  // Steady arms: the largest uplift of each over all pantographs, in the analysis section.
  double x0 = 0.0, x1 = 0.0;
  analysis_section(m, &x0, &x1);
  std::map<long long, double> arms;
  for (const auto& per : max_uplift_)
    for (const auto& [key, up] : per) {
      const auto it = arms.find(key);
      if (it == arms.end()) arms.emplace(key, up);
      else it->second = std::max(it->second, up);
    }
  for (const auto& [key, up] : arms) {
    const double xs = 1e-3 * key;
    if (xs < x0 - 1e-6 || xs > x1 + 1e-6) continue;
    SteadyArmStatistics a;
    a.station = xs;
    a.max_uplift = up;
    a.exceeded = m.scene.output.allowed_uplift && up > *m.scene.output.allowed_uplift;
    ls.steady_arms.push_back(a);
  }
  return ls;
}

std::vector<std::string> PassRecorder::processed_columns() const {
  std::vector<std::string> c;
  for (const std::string& name : names_) {
    c.push_back(name + "_position_m");
    c.push_back(name + "_force_filtered_N");
    c.push_back(name + "_force_measured_N");
  }
  return c;
}

std::vector<std::string> PassRecorder::dropper_columns() const {
  std::vector<std::string> c;
  char buf[64];
  for (const DropperTrack& t : droppers_) {
    std::snprintf(buf, sizeof buf, "dropper_at_%.2f_m_N", t.station);
    c.push_back(buf);
  }
  return c;
}

std::vector<PassRecorder::Row> PassRecorder::processed_rows(const Model& m) const {
  const std::size_t np = m.pantographs.size();
  std::vector<std::vector<double>> filtered(np), measured(np);
  for (std::size_t p = 0; p < np; ++p) {
    filtered[p] = lowpass_zero_phase(force_[p], 1.0 / m.dt, m.scene.output.filter_cutoff);
    measured[p] = measured_force(m, p);
  }
  std::vector<Row> out;
  out.reserve(row_index_.size());
  for (std::size_t i : row_index_) {
    Row r{time_[i], {}};
    for (std::size_t p = 0; p < np; ++p) {
      r.values.push_back(position_[p][i] + 0.0);
      r.values.push_back(filtered[p][i]);
      r.values.push_back(measured[p].size() > i ? measured[p][i] : std::nan(""));
    }
    out.push_back(std::move(r));
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
                            const RunInfo& run, const LineStatistics* line) {
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
  if (m.sections.size() > 1) {
    // The transition supports' rise d (eq. 8, or overlap.support_rise): what an overlap study varies.
    Json rises = Json::array();
    for (const Section& sec : m.sections) rises.push_back({{"first_m", sec.rise_first}, {"last_m", sec.rise_last}});
    j["section_support_rises"] = rises;
  }
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
    Json losses;
    losses["count"] = p.loss_events.size();
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
    losses["events_truncated"] = p.loss_events.size() > kMaxEvents;
    pj["contact_loss_events"] = losses;
    Json sp;
    sp["span_passing_hz"] = p.spectrum.span_passing_hz;
    sp["dropper_passing_hz"] = p.spectrum.dropper_passing_hz;
    sp["resolution_hz"] = p.spectrum.resolution_hz;
    sp["segment_s"] = p.spectrum.segment_s;
    sp["segments"] = p.spectrum.segments;
    Json peaks = Json::array();
    for (const SpectralPeak& k : p.spectrum.peaks)
      peaks.push_back(Json{{"frequency_hz", k.frequency}, {"psd_N2_per_hz", k.psd}, {"amplitude_N", k.amplitude}});
    sp["peaks"] = peaks;
    pj["spectrum"] = sp;
    if (p.target_mean) {
      const PantographStatistics::TargetMean& t = *p.target_mean;
      const TargetMeanForce* spec = nullptr;
      for (const PantographSpec& ps : scene.pantographs)
        if (ps.name == p.name && ps.target_mean_force) spec = &*ps.target_mean_force;
      Json tj{{"speed_kmh", 3.6 * t.speed_mps}, {"target_N", t.target}, {"mean_N", p.filtered.mean},
              {"difference_N", t.difference}, {"tolerance_N", t.tolerance ? Json(*t.tolerance) : Json(nullptr)},
              {"within", t.within}};
      if (spec) tj["curve"] = Json{{"a", spec->a}, {"b", spec->b}, {"speed_unit", spec->speed_kmh ? "km/h" : "m/s"}};
      pj["target_mean_force"] = tj;
    } else {
      pj["target_mean_force"] = nullptr;
    }
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
    pantographs.push_back(pj);
  }
  j["pantographs"] = pantographs;
  if (line) {
    const OutputSpec& o = scene.output;
    auto opt = [](const std::optional<double>& v) { return v ? Json(*v) : Json(nullptr); };
    j["allowed_uplift_m"] = opt(o.allowed_uplift);
    Json arms = Json::array();
    for (const SteadyArmStatistics& a : line->steady_arms)
      arms.push_back(Json{{"station_m", a.station}, {"max_uplift_m", a.max_uplift}, {"exceeded", a.exceeded}});
    j["steady_arms"] = arms;
    Json dr;
    dr["rainflow_bin_N"] = line->range_bin_n;
    Json list = Json::array();
    for (const DropperStatistics& d : line->droppers)
      list.push_back(Json{{"station_m", d.station},       {"static_tension_N", d.static_tension},
                          {"max_force_N", d.max_force},   {"min_force_N", d.min_force},
                          {"slack_percent", d.slack_percent}, {"rainflow_cycles", d.cycles},
                          {"max_range_N", d.max_range}});
    dr["list"] = list;
    j["droppers"] = dr;
    Json supports = Json::array();
    for (double x : m.support_x) supports.push_back(x);
    j["support_stations_m"] = supports;
    Json dst = Json::array();
    for (int k : m.dropper_order) dst.push_back(m.droppers[k].x);
    j["dropper_stations_m"] = dst;
    // The scene's limits, each against the worst pantograph.
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
    for (const SteadyArmStatistics& a : line->steady_arms) uplift = std::max(uplift, a.max_uplift);
    mark("stat_max_force_N", o.max_stat_force, true, stat_max);
    mark("stat_min_force_N", o.min_stat_force, false, stat_min);
    mark("contact_loss_percent", o.max_contact_loss_percent, true, loss);
    mark("max_uplift_m", o.allowed_uplift, true, uplift);
    j["limits"] = limits;
  }
  // Replace invalid UTF-8 in names rather than throw: a scene name is the user's text.
  return j.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

}  // namespace catenary_sim
