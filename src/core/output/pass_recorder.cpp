#include "catenary_sim/core/output/pass_recorder.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "catenary_sim/core/output/zero_phase_filter.hpp"
#include "output/steady_arms_near.hpp"

namespace catenary_sim {

namespace {

// The time series' column of steady arm k (of `arms`). Sections overlapping over more than one span
// share supports: there each section's arm is named with its section, so that no name appears twice.
std::string steady_arm_column(const Model& m, const std::vector<int>& arms, int k) {
  const SupportSpring& sp = m.springs[k];
  const bool shared =
      std::count_if(arms.begin(), arms.end(), [&](int j) { return m.springs[j].span_index == sp.span_index; }) > 1;
  std::string name = "uplift_steady_arm" + std::to_string(sp.span_index);
  if (shared) name += "_s" + std::to_string(m.wires[wire_holding(m, sp.dof)].section);
  return name + "_m";
}

}  // namespace

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
      t.messenger_dof = m.droppers[k].messenger_dof;
      t.contact_dof = m.droppers[k].contact_dof;
      t.static_tension = m.droppers[k].static_tension;
      t.stiffness = m.droppers[k].stiffness;
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
    for (int k : steady_arm_springs_) columns_.push_back(steady_arm_column(m, steady_arm_springs_, k));
  analysis_section(m, &x0_, &x1_);
  running_ = m.endless;
  if (!running_) return;
  const double fs = 1.0 / m.dt;
  run_.resize(np);
  for (Running& r : run_) {
    r.wire_sum.assign(nw, 0.0);
    r.wire_max.assign(nw, 0.0);
    r.wire_on.assign(nw, 0);
  }
  buf_.x.resize(np);
  buf_.force.resize(np);
  buf_.measured.resize(np);
  head_history_.resize(np);
  // The overlap of the filter's blocks: kFilterSettling time constants of the lowest cutoff that
  // filters at all (lowpass_zero_phase passes a cutoff at or above Nyquist through).
  double fc = m.scene.output.filter_cutoff < 0.5 * fs ? m.scene.output.filter_cutoff : 0.0;
  for (std::size_t p = 0; p < np; ++p) {
    const Pantograph& pg = m.pantographs[p];
    if (pg.moving_force) continue;
    head_history_[p].assign(9 * (pg.heads.empty() ? 1 : pg.heads.size()), 0.0);
    const double bw = m.scene.output.sensor_bandwidth;
    if (bw < 0.5 * fs && (fc == 0.0 || bw < fc)) fc = bw;
  }
  margin_ = fc > 0.0 ? static_cast<std::size_t>(std::ceil(kFilterSettling * fs / fc)) : 4;
  block_ = std::max<std::size_t>(margin_, 256);
  window_steps_ = static_cast<std::size_t>(std::ceil(kSpectrumWindow * fs));
}

namespace {

// A dropper's force as the explicit integrator decides it: elastic tension, nothing when slack.
// On a 3-D line the stretch has the lean's share (LateralState::dropper_stretch, lateral.hpp):
// a leaning dropper is a stiff link along itself, so the vertical plane gives way to a change of
// lean by about as much (u_m - u_c ~ -lean), and the vertical stretch alone would read k times
// the lean's change (60 N per 0.3 mm) as force or slack the dropper does not have.
// A dropper at the step's middle (numerics.droppers implicit) reports the tension it acted with
// over the last step (State::dropper_tension; NaN before the first step and once a moving window
// has left it, when the elastic tension is the one). The dropper `k`'s data come from its track (DropperTrack), not the model's list.
inline double dropper_force(const Model& m, const State& s, std::size_t k, int messenger_dof, int contact_dof,
                            double static_tension, double stiffness, bool* slack) {
  double t = s.dropper_tension.empty() || !m.dropper_at_middle[k] ? std::nan("") : s.dropper_tension[k];
  if (std::isnan(t)) {
    double stretch = s.u[messenger_dof] - s.u[contact_dof];
    if (m.lateral && !s.lateral.dropper_stretch.empty()) stretch += s.lateral.dropper_stretch[k];
    t = static_tension + stiffness * stretch;
  }
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
  ++steps_;
  if (running_) {
    record_running(m, s);
  } else {
    time_.push_back(s.time);
    record_whole(m, s);
  }
  // The samples run from the first recorded state: a recorder started after a reset that kept the
  // clock running samples at its rate from there, not every step until it reaches the clock.
  if (steps_ == 1) next_sample_ = s.time;
  if (sample_period_ > 0.0 && s.time + 1e-12 < next_sample_) return;
  next_sample_ += sample_period_;
  if (running_) pending_rows_.push_back(steps_ - 1);
  else row_index_.push_back(time_.size() - 1);
  if (m.scene.output.dropper_series && !droppers_.empty()) {
    Row dr{s.time, {}};
    dr.values.reserve(droppers_.size());
    bool slack = false;
    for (const DropperTrack& t : droppers_)
      dr.values.push_back(dropper_force(m, s, t.index, t.messenger_dof, t.contact_dof, t.static_tension, t.stiffness, &slack));
    dropper_rows_.push_back(std::move(dr));
  }
  Row row{s.time, {}};
  row.values.reserve(columns_.size());
  for (std::size_t p = 0; p < np; ++p) {
    const Pantograph& pg = m.pantographs[p];
    row.values.push_back(s.front - pg.position + s.line_offset + 0.0);  // + 0.0: no "-0" in the CSV
    for (int ci : pg.collectors)
      for (std::size_t w = 0; w < nw; ++w) row.values.push_back(s.contact_force_on(m, ci, static_cast<int>(w)));
    row.values.push_back(total_contact_force(m, s, static_cast<int>(p)));
    row.values.push_back(pg.moving_force ? 0.0 : s.pantograph_displacement(m, static_cast<int>(p), 0));
  }
  if (!m.endless)
    for (int k : steady_arm_springs_) row.values.push_back(s.support_uplift(m, k));
  rows_.push_back(std::move(row));
  if (running_ && rows_.size() > kMaxRows) rows_.pop_front();
}

void PassRecorder::record_whole(const Model& m, const State& s) {
  const std::size_t np = m.pantographs.size(), nw = m.contact_wires.size();
  // dropper_force() with the dropper's data at hand in its track: without the model's dropper list
  // in the cache at every step.
  for (DropperTrack& t : droppers_) {
    bool slack = false;
    const double f = dropper_force(m, s, t.index, t.messenger_dof, t.contact_dof, t.static_tension, t.stiffness, &slack);
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
      const int nm = pg.masses_count(), pi = static_cast<int>(p);
      const double top = s.pantograph_displacement(m, pi, 0);  // the chain's first mass: head or top frame
      if (pg.heads.empty()) {
        const double stretch = (nm > 1 ? s.pantograph_displacement(m, pi, 1) : 0.0) - top;
        double fe = pg.spring_preload[0] + pg.stiffness[0] * stretch;
        if (nm == 1) fe += s.uplift[p] + pg.aero_coefficient * air_speed_squared(s, p);
        head_u_[p].push_back(top);
        suspension_stretch_[p].push_back(stretch);
        suspension_force_[p].push_back(fe);
      } else {
        // Every head's own suspension to the top frame mass (and its own aero force, which acts
        // on the head), one entry per head per step: the load cells sit under each head.
        for (const Head& h : pg.heads) {
          const double stretch = top - s.u[h.dof];
          head_u_[p].push_back(s.u[h.dof]);
          suspension_stretch_[p].push_back(stretch);
          suspension_force_[p].push_back(h.preload + h.stiffness * stretch + h.aero_coefficient * air_speed_squared(s, p));
        }
      }
    }
    const double xp = s.front - pg.position;  // model station
    position_[p].push_back(xp + s.line_offset);
    force_[p].push_back(total_contact_force(m, s, static_cast<int>(p)));
    for (std::size_t w = 0; w < nw; ++w)
      wire_force_[p][w].push_back(s.pantograph_force_on(m, static_cast<int>(p), static_cast<int>(w)));
    for_each_steady_arm_near(m, steady_arm_springs_, steady_arm_x_, longest_span_, s.line_offset, xp,
                             [&](const SupportSpring& sp, long long key) {
                               const auto it = max_uplift_[p].find(key);
                               if (it == max_uplift_[p].end()) max_uplift_[p].emplace(key, s.u[sp.dof]);
                               else it->second = std::max(it->second, s.u[sp.dof]);
                             });
  }
}

std::vector<PantographStatistics> PassRecorder::statistics(const Model& m) const {
  return statistics(m, m.scene.output.filter_cutoff);
}

std::size_t PassRecorder::memory_bytes() const {
  std::size_t b = 0;
  auto vec = [&](const std::vector<double>& v) { b += v.capacity() * sizeof(double); };
  auto vecs = [&](const std::vector<std::vector<double>>& v) {
    for (const auto& x : v) vec(x);
  };
  auto rows = [&](const std::deque<Row>& d) {
    for (const Row& r : d) b += sizeof(Row) + r.values.capacity() * sizeof(double);
  };
  vec(time_);
  vecs(position_);
  vecs(force_);
  for (const auto& w : wire_force_) vecs(w);
  vecs(head_u_);
  vecs(suspension_stretch_);
  vecs(suspension_force_);
  for (const auto& a : max_uplift_) b += a.size() * (sizeof(long long) + sizeof(double) + 32);
  for (const DropperTrack& t : droppers_) b += t.reversals.capacity() * sizeof(double);
  b += row_index_.capacity() * sizeof(std::size_t);
  rows(rows_);
  rows(dropper_rows_);
  rows(processed_);
  vec(buf_.time);
  vecs(buf_.x);
  vecs(buf_.force);
  vecs(buf_.measured);
  vecs(head_history_);
  b += pending_rows_.size() * sizeof(std::size_t);
  b += arms_.size() * (sizeof(long long) + sizeof(double) + 32);
  for (const Running& r : run_) b += r.window.size() * sizeof(double) + r.listed.capacity() * sizeof(ContactLossEvent);
  return b;
}

std::vector<PantographStatistics> PassRecorder::statistics(const Model& m, double cutoff_hz) const {
  if (running_) return running_statistics(m, cutoff_hz);
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
    st.loss_events_total = st.loss_events.size();
    st.loss_events_per_km = x1 > x0 ? st.loss_events.size() / ((x1 - x0) / 1000.0) : std::nan("");
    st.longest_loss_s = 0.0;
    for (const ContactLossEvent& e : st.loss_events) st.longest_loss_s = std::max(st.longest_loss_s, e.duration);
    st.spectrum = spectrum_summary(m, section_speed(time_, position_[p], x0, x1), spectrum(m, p));
    measured_statistics(m, p, x0, x1, filtered, &st.measured);
    st.target_mean = target_mean(m.scene.pantographs[p].target_mean_force, section_speed(time_, position_[p], x0, x1),
                                 st.filtered.mean);
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

// Median spacing of consecutive droppers within a span over [x0, x1]; NaN without droppers. Those
// the contact wire hangs from count: on a compound line its hangers.
double dropper_spacing(const Model& m, double x0, double x1) {
  std::vector<double> gaps;
  const Dropper* last = nullptr;
  const bool compound = std::any_of(m.droppers.begin(), m.droppers.end(), [](const Dropper& d) { return d.hanger; });
  for (int k : m.dropper_order) {
    const Dropper& d = m.droppers[k];
    if (d.x < x0 || d.x > x1 || (compound && !d.hanger)) continue;
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
  double v = 0.0;
  if (running_) {
    const Running& r = run_[p];
    in.assign(r.window.begin(), r.window.end());
    v = r.any_in && r.in_t > r.first_t ? (r.in_x - r.first_x) / (r.in_t - r.first_t) : std::nan("");
  } else {
    for (std::size_t i = 0; i < force_[p].size(); ++i)
      if (position_[p][i] >= x0 && position_[p][i] <= x1) in.push_back(force_[p][i]);
    v = section_speed(time_, position_[p], x0, x1);
  }
  const double fs = 1.0 / m.dt;
  // Segments of 8 span-passing periods (a resolution of 1/8 of the span-passing frequency), or the
  // whole section when it is shorter.
  std::size_t seg = in.size();
  if (v > 0.0) seg = std::min(seg, static_cast<std::size_t>(std::ceil(8.0 * mean_span(m, x0, x1) / v * fs)));
  return welch_psd(in, fs, seg);
}

std::vector<Spectrum> PassRecorder::spectra(const Model& m) const {
  std::vector<Spectrum> out;
  for (std::size_t p = 0; p < m.pantographs.size(); ++p) out.push_back(spectrum(m, p));
  return out;
}

SpectrumSummary PassRecorder::spectrum_summary(const Model& m, double v, const Spectrum& sp) const {
  double x0 = 0.0, x1 = 0.0;
  analysis_section(m, &x0, &x1);
  SpectrumSummary s;
  s.span_passing_hz = v / mean_span(m, x0, x1);
  s.dropper_passing_hz = v / dropper_spacing(m, x0, x1);
  s.resolution_hz = sp.resolution;
  s.segment_s = sp.segment * m.dt;
  s.segments = sp.segments;
  s.peaks = spectral_peaks(sp, 2.0 * sp.resolution, kSpectrumMaxHz, 5);
  return s;
}

double PassRecorder::max_steady_arm_uplift(double station) const {
  const long long key = std::llround(1e3 * station);  // the key of record()
  double up = std::nan("");
  for (const auto& per : max_uplift_) {
    const auto it = per.find(key);
    if (it != per.end()) up = std::isnan(up) ? it->second : std::max(up, it->second);
  }
  return up;
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
    ds.hanger = d.hanger;
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
  std::map<long long, double> arms = arms_;  // (an endless pass's, already over all pantographs)
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
    // (An endless line's arms are its block's, repeated span by span.)
    auto same_arm = [&](double x) { return std::abs(m.endless ? std::remainder(x - xs, m.endless_span) : x - xs) < 1e-3; };
    for (const SupportSpring& sp : m.springs)
      if (sp.hinged_arm() && same_arm(sp.x)) {
        a.hinged = true;
        a.stiffness = sp.static_stiffness();  // k_A, with the share a 3-D line's lateral plane gives
        a.pull_off = sp.arm_pull_off;
        a.inclination = sp.arm_inclination;
        a.inclination_at_max_uplift = sp.arm_inclination_at(up);
        a.registration_travel = sp.arm_end_travel(up);
        break;
      }
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

std::deque<PassRecorder::Row> PassRecorder::processed_rows(const Model& m) const {
  if (running_) {
    std::deque<Row> out = processed_;
    std::deque<std::size_t> pending = pending_rows_;
    commit(m, first_ + buf_.time.size(), true, nullptr, &out, &pending);
    while (out.size() > rows_.size()) out.pop_front();  // the same rows as rows() keeps
    return out;
  }
  const std::size_t np = m.pantographs.size();
  std::vector<std::vector<double>> filtered(np), measured(np);
  for (std::size_t p = 0; p < np; ++p) {
    filtered[p] = lowpass_zero_phase(force_[p], 1.0 / m.dt, m.scene.output.filter_cutoff);
    measured[p] = measured_force(m, p);
  }
  std::deque<Row> out;
  for (std::size_t i : row_index_) {
    Row r{time_[i], {}};
    for (std::size_t p = 0; p < np; ++p) {
      r.values.push_back(position_[p][i] + 0.0);
      r.values.push_back(filtered[p][i]);
      // A moving force has no head: what it applies is what a load cell under it would read.
      r.values.push_back(m.pantographs[p].moving_force ? force_[p][i]
                         : measured[p].size() > i  ? measured[p][i]
                                                   : std::nan(""));
    }
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace catenary_sim
