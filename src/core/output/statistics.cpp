#include "catenary_sim/core/output/statistics.hpp"

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

void PassRecorder::Moments::add(double v) {
  if (n == 0) min = max = v;
  ++n;
  const double d = v - mean;
  mean += d / static_cast<double>(n);
  m2 += d * (v - mean);
  min = std::min(min, v);
  max = std::max(max, v);
}

ForceStatistics PassRecorder::Moments::statistics() const {
  if (n == 0) return force_statistics({});
  ForceStatistics s;
  s.mean = mean;
  s.std_dev = std::sqrt(std::max(0.0, m2 / static_cast<double>(n)));
  s.max = max;
  s.min = min;
  s.stat_max = s.mean + 3.0 * s.std_dev;
  s.stat_min = s.mean - 3.0 * s.std_dev;
  return s;
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

// The standards' permissible mean force Fm(v) against the pass's (filtered) mean, at the section's
// mean speed v; none without a target or with no mean.
std::optional<PantographStatistics::TargetMean> target_mean(const Model& m, std::size_t p, double v, double mean) {
  const std::optional<TargetMeanForce>& target = m.scene.pantographs[p].target_mean_force;
  if (!target || !std::isfinite(v) || !std::isfinite(mean)) return std::nullopt;
  PantographStatistics::TargetMean t;
  t.speed_mps = v;
  t.target = target->at(v);
  t.difference = mean - t.target;
  t.tolerance = target->tolerance;
  t.within = !t.tolerance || std::fabs(t.difference) <= *t.tolerance;
  return t;
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
    for (const DropperTrack& t : droppers_) dr.values.push_back(dropper_force(m, t.index, s, &slack));
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
}

std::vector<PantographStatistics> PassRecorder::statistics(const Model& m) const {
  return statistics(m, m.scene.output.filter_cutoff);
}

namespace {

// The measuring pantograph's force at the middle of three steps (slots a, b, c of a head history
// of u, stretch and force per head): PassRecorder::measured_force's sum, one step at a time.
double measured_at(const Pantograph& pg, const std::vector<double>& h, std::size_t a, std::size_t b, std::size_t c,
                   double dt) {
  const std::size_t heads = pg.heads.empty() ? 1 : pg.heads.size();
  double f = 0.0;
  for (std::size_t k = 0; k < heads; ++k) {
    const double mass = pg.heads.empty() ? pg.masses[0] : pg.heads[k].mass;
    const double damping = pg.heads.empty() ? pg.damping[0] : pg.heads[k].damping;
    auto at = [&](std::size_t slot, int what) { return h[(slot * heads + k) * 3 + what]; };
    const double vel = (at(c, 1) - at(a, 1)) / (2.0 * dt);
    const double acc = (at(c, 0) - 2.0 * at(b, 0) + at(a, 0)) / (dt * dt);
    f += at(b, 2) + damping * vel - mass * acc;
  }
  return f;
}

void close_loss(double t_end, double x_end, ContactLossEvent* ev, std::size_t* events,
                double* longest, std::vector<ContactLossEvent>* listed) {
  ev->duration = t_end - ev->start_time;
  ev->length = x_end - ev->station;
  ++*events;
  *longest = std::max(*longest, ev->duration);
  if (listed->size() < PassRecorder::kMaxListed) listed->push_back(*ev);
}

}  // namespace

void PassRecorder::record_running(const Model& m, const State& s) {
  const std::size_t np = m.pantographs.size(), nw = m.contact_wires.size();
  const std::size_t i = steps_ - 1;  // this step
  const bool has_prev = !buf_.time.empty();
  const double t_prev = has_prev ? buf_.time.back() : 0.0;
  buf_.time.push_back(s.time);
  for (std::size_t p = 0; p < np; ++p) {
    const Pantograph& pg = m.pantographs[p];
    Running& r = run_[p];
    const double xp = s.front - pg.position, x = xp + s.line_offset;
    const double f = total_contact_force(m, s, static_cast<int>(p));
    const double x_prev = has_prev ? buf_.x[p].back() : 0.0;
    buf_.x[p].push_back(x);
    buf_.force[p].push_back(f);
    if (!pg.moving_force) {
      // The head's suspension as record_whole() keeps it, for the last three steps.
      std::vector<double>& h = head_history_[p];
      const std::size_t heads = pg.heads.empty() ? 1 : pg.heads.size(), slot = i % 3;
      const int nm = pg.masses_count(), pi = static_cast<int>(p);
      const double top = s.pantograph_displacement(m, pi, 0);  // the chain's first mass: head or top frame
      for (std::size_t k = 0; k < heads; ++k) {
        double* e = &h[(slot * heads + k) * 3];
        if (pg.heads.empty()) {
          const double stretch = (nm > 1 ? s.pantograph_displacement(m, pi, 1) : 0.0) - top;
          double fe = pg.spring_preload[0] + pg.stiffness[0] * stretch;
          if (nm == 1) fe += s.uplift[p] + pg.aero_coefficient * air_speed_squared(s, p);
          e[0] = top;
          e[1] = stretch;
          e[2] = fe;
        } else {
          const Head& hd = pg.heads[k];
          const double stretch = top - s.u[hd.dof];
          e[0] = s.u[hd.dof];
          e[1] = stretch;
          e[2] = hd.preload + hd.stiffness * stretch + hd.aero_coefficient * air_speed_squared(s, p);
        }
      }
      if (i >= 2) {
        const double fm = measured_at(pg, h, (i - 2) % 3, (i - 1) % 3, slot, m.dt);
        if (i == 2) buf_.measured[p].push_back(fm);  // the first step takes the second's (as measured_force)
        buf_.measured[p].push_back(fm);
      }
    }
    if (x < x0_ || x > x1_) {
      if (r.open) {
        // Leaving the section cuts a running loss at this step.
        close_loss(s.time, x, &r.event, &r.events, &r.longest, &r.listed);
        r.open = false;
      }
    } else {
      if (!r.any_in) {
        r.first_t = s.time;
        r.first_x = x;
      }
      r.any_in = true;
      r.in_dt = has_prev ? s.time - t_prev : 0.0;
      r.in_dx = has_prev ? x - x_prev : 0.0;
      r.in_t = s.time;
      r.in_x = x;
      r.unfiltered.add(f);
      r.lost += f <= 0.0;
      for (std::size_t w = 0; w < nw; ++w) {
        const double fw = s.pantograph_force_on(m, static_cast<int>(p), static_cast<int>(w));
        r.wire_sum[w] += fw;
        r.wire_max[w] = std::max(r.wire_max[w], fw);
        r.wire_on[w] += fw > 0.0;
      }
      const bool lost = !(f > 0.0);
      if (lost && !r.open) {
        r.event = ContactLossEvent{};
        r.event.start_time = s.time;
        r.event.station = x;
        r.open = true;
      } else if (!lost && r.open) {
        close_loss(s.time, x, &r.event, &r.events, &r.longest, &r.listed);
        r.open = false;
      }
      r.window.push_back(f);
      if (r.window.size() > window_steps_) r.window.pop_front();
    }
    // Steady arms within half a span, as record_whole() finds them; the line's arms by station.
    const auto first = std::lower_bound(steady_arm_x_.begin(), steady_arm_x_.end(), xp - longest_span_);
    for (std::size_t k = first - steady_arm_x_.begin(); k < steady_arm_x_.size() && steady_arm_x_[k] <= xp + longest_span_; ++k) {
      const SupportSpring& sp = m.springs[steady_arm_springs_[k]];
      const int span = sp.span_index;
      const double reach = 0.5 * std::min(m.scene.spans[span - 1], m.scene.spans[span]);
      if (std::fabs(xp - sp.x) > reach) continue;
      const long long key = std::llround(1e3 * (sp.x + s.line_offset));
      const double up = s.u[sp.dof], xs = 1e-3 * key;
      if (xs >= x0_ - 1e-6 && xs <= x1_ + 1e-6) r.uplift = std::max(r.uplift, up);
      const auto it = arms_.find(key);
      if (it == arms_.end()) arms_.emplace(key, up);
      else it->second = std::max(it->second, up);
    }
  }
  while (arms_.size() > kMaxListed) arms_.erase(arms_.begin());  // the oldest: the train runs forward
  // A block is settled once kFilterSettling time constants follow it (one more step for the
  // measured force's central difference).
  if (steps_ >= committed_ + block_ + margin_ + 2) {
    const std::size_t end = committed_ + block_;
    commit(m, end, false, &run_, &processed_, &pending_rows_);
    committed_ = end;
    const std::size_t drop = committed_ - margin_ - first_;  // keep a margin before the next block
    auto trim = [drop](std::vector<double>& v) { v.erase(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(std::min(drop, v.size()))); };
    trim(buf_.time);
    for (std::size_t p = 0; p < np; ++p) {
      trim(buf_.x[p]);
      trim(buf_.force[p]);
      trim(buf_.measured[p]);
    }
    first_ += drop;
  }
}

void PassRecorder::commit(const Model& m, std::size_t end, bool final, std::vector<Running>* run, std::deque<Row>* processed,
                          std::deque<std::size_t>* pending) const {
  const std::size_t np = m.pantographs.size();
  const double fs = 1.0 / m.dt;
  std::vector<std::vector<double>> filtered(np), measured(np);
  for (std::size_t p = 0; p < np; ++p) {
    filtered[p] = lowpass_zero_phase(buf_.force[p], fs, m.scene.output.filter_cutoff);
    if (m.pantographs[p].moving_force || steps_ < 3) continue;
    std::vector<double> raw = buf_.measured[p];
    if (final) raw.push_back(raw.back());  // the last step takes the one before (as measured_force)
    measured[p] = lowpass_zero_phase(raw, fs, m.scene.output.sensor_bandwidth);
  }
  for (std::size_t p = 0; p < np && run; ++p) {
    Running& r = (*run)[p];
    for (std::size_t j = committed_; j < end; ++j) {
      const std::size_t k = j - first_;
      const double x = buf_.x[p][k];
      if (x < x0_ || x > x1_) continue;
      r.filtered.add(filtered[p][k]);
      if (k >= measured[p].size()) continue;
      r.measured.add(measured[p][k]);
      const double diff = measured[p][k] - filtered[p][k];
      r.diff_sq += diff * diff;
      r.diff_max = std::max(r.diff_max, std::fabs(diff));
    }
  }
  while (processed && pending && !pending->empty() && pending->front() < end) {
    const std::size_t k = pending->front() - first_;
    pending->pop_front();
    Row row{buf_.time[k], {}};
    for (std::size_t p = 0; p < np; ++p) {
      row.values.push_back(buf_.x[p][k] + 0.0);
      row.values.push_back(filtered[p][k]);
      // A moving force has no head: what it applies is what a load cell under it would read.
      row.values.push_back(m.pantographs[p].moving_force ? buf_.force[p][k]
                                                         : k < measured[p].size() ? measured[p][k] : std::nan(""));
    }
    processed->push_back(std::move(row));
    if (processed->size() > kMaxRows) processed->pop_front();
  }
}

std::vector<PantographStatistics> PassRecorder::running_statistics(const Model& m, double cutoff_hz) const {
  std::vector<Running> run = run_;
  commit(m, first_ + buf_.time.size(), true, &run, nullptr, nullptr);
  const double fs = 1.0 / m.dt;
  std::vector<PantographStatistics> out;
  for (std::size_t p = 0; p < m.pantographs.size(); ++p) {
    Running& r = run[p];
    PantographStatistics st;
    st.name = m.pantographs[p].name;
    st.samples = r.unfiltered.n;
    st.unfiltered = r.unfiltered.statistics();
    if (cutoff_hz == m.scene.output.filter_cutoff) {
      st.filtered = r.filtered.statistics();
    } else {
      // Another cutoff than the one filtered as the pass ran: over the spectrum's window.
      const std::vector<double> w(r.window.begin(), r.window.end());
      st.filtered = force_statistics(lowpass_zero_phase(w, fs, cutoff_hz));
    }
    const double n = static_cast<double>(r.unfiltered.n);
    st.contact_loss_percent = r.unfiltered.n ? 100.0 * r.lost / n : std::nan("");
    st.max_uplift_at_support_m = r.uplift > -1e300 ? r.uplift : std::nan("");
    for (std::size_t w = 0; w < m.contact_wires.size(); ++w) {
      WireContactStatistics ws;
      ws.wire = m.wires[m.contact_wires[w]].name;
      ws.mean_force = r.unfiltered.n ? r.wire_sum[w] / n : std::nan("");
      ws.max_force = r.wire_max[w];
      ws.contact_percent = r.unfiltered.n ? 100.0 * r.wire_on[w] / n : std::nan("");
      st.wires.push_back(ws);
    }
    if (r.open) {
      // Still lost at the last step in the section: it stands for one step.
      close_loss(r.in_t + r.in_dt, r.in_x + r.in_dx, &r.event, &r.events, &r.longest, &r.listed);
      r.open = false;
    }
    st.loss_events = r.listed;
    st.loss_events_total = r.events;
    // Per km run in the section so far (the section's length once the pass is through it).
    const double run_km = (r.in_x - r.first_x) / 1000.0;
    st.loss_events_per_km = r.any_in && run_km > 0.0 ? r.events / run_km : std::nan("");
    st.longest_loss_s = r.longest;
    const double v = r.any_in && r.in_t > r.first_t ? (r.in_x - r.first_x) / (r.in_t - r.first_t) : std::nan("");
    st.spectrum = spectrum_summary(m, v, spectrum(m, p));
    if (!m.pantographs[p].moving_force && r.measured.n) {
      st.measured.available = true;
      st.measured.force = r.measured.statistics();
      st.measured.rms_difference = std::sqrt(r.diff_sq / static_cast<double>(r.measured.n));
      st.measured.max_abs_difference = r.diff_max;
    }
    st.measured.bandwidth_hz = m.scene.output.sensor_bandwidth;
    st.target_mean = target_mean(m, p, v, st.filtered.mean);
    out.push_back(st);
  }
  return out;
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
  for (const DropperTrack& t : droppers_) b += t.reversals.points().capacity() * sizeof(double);
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
    st.target_mean = target_mean(m, p, section_speed(time_, position_[p], x0, x1), st.filtered.mean);
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
    // (the same value on a finite line; an endless one lists only its last arms)
    for (const PantographStatistics& p : stats) uplift = std::max(uplift, p.max_uplift_at_support_m);
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
