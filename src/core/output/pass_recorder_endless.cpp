// The recorder on an endless line (pass_recorder.hpp): running statistics in bounded memory. The
// force is filtered in blocks that overlap by kFilterSettling time constants, so what is committed
// equals the whole-record zero-phase filter's result to rounding.
#include "catenary_sim/core/output/pass_recorder.hpp"

#include <algorithm>
#include <cmath>

#include "catenary_sim/core/output/zero_phase_filter.hpp"
#include "output/steady_arms_near.hpp"

namespace catenary_sim {

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
  const std::size_t np = m.pantographs.size();
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
    if (!pg.moving_force) record_head(m, s, p);
    if (x < x0_ || x > x1_) {
      if (r.open) {
        // Leaving the section cuts a running loss at this step.
        close_loss(s.time, x, &r.event, &r.events, &r.longest, &r.listed);
        r.open = false;
      }
    } else {
      record_in_section(m, s, p, x, f, has_prev ? s.time - t_prev : 0.0, has_prev ? x - x_prev : 0.0);
    }
    record_steady_arms(m, s, xp, &r);
  }
  while (arms_.size() > kMaxListed) arms_.erase(arms_.begin());  // the oldest: the train runs forward
  // A block is settled once kFilterSettling time constants follow it (one more step for the
  // measured force's central difference).
  if (steps_ >= committed_ + block_ + margin_ + 2) settle_block(m);
}

void PassRecorder::record_head(const Model& m, const State& s, std::size_t p) {
  const Pantograph& pg = m.pantographs[p];
  const std::size_t i = steps_ - 1;  // this step
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

void PassRecorder::record_in_section(const Model& m, const State& s, std::size_t p, double x, double f, double dt,
                                     double dx) {
  const std::size_t nw = m.contact_wires.size();
  Running& r = run_[p];
  if (!r.any_in) {
    r.first_t = s.time;
    r.first_x = x;
  }
  r.any_in = true;
  r.in_dt = dt;
  r.in_dx = dx;
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
void PassRecorder::record_steady_arms(const Model& m, const State& s, double xp, Running* r) {
  for_each_steady_arm_near(m, steady_arm_springs_, steady_arm_x_, longest_span_, s.line_offset, xp,
                           [&](const SupportSpring& sp, long long key) {
                             const double up = s.u[sp.dof], xs = 1e-3 * key;
                             if (xs >= x0_ - 1e-6 && xs <= x1_ + 1e-6) r->uplift = std::max(r->uplift, up);
                             const auto it = arms_.find(key);
                             if (it == arms_.end()) arms_.emplace(key, up);
                             else it->second = std::max(it->second, up);
                           });
}

void PassRecorder::settle_block(const Model& m) {
  const std::size_t end = committed_ + block_;
  commit(m, end, false, &run_, &processed_, &pending_rows_);
  committed_ = end;
  const std::size_t drop = committed_ - margin_ - first_;  // keep a margin before the next block
  auto trim = [drop](std::vector<double>& v) { v.erase(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(std::min(drop, v.size()))); };
  trim(buf_.time);
  for (std::size_t p = 0; p < m.pantographs.size(); ++p) {
    trim(buf_.x[p]);
    trim(buf_.force[p]);
    trim(buf_.measured[p]);
  }
  first_ += drop;
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
    st.target_mean = target_mean(m.scene.pantographs[p].target_mean_force, v, st.filtered.mean);
    out.push_back(st);
  }
  return out;
}

}  // namespace catenary_sim
