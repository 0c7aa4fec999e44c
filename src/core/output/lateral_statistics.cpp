#include "catenary_sim/core/output/lateral_statistics.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace catenary_sim {

namespace {
constexpr double kBlowOffPeriod = 0.005;  // s: the wind moves the wires at a few Hz at most
}

LateralRecorder::LateralRecorder(const Model& m, double sample_rate_hz)
    : sample_period_(sample_rate_hz > 0.0 ? 1.0 / sample_rate_hz : 0.0), endless_(m.endless) {
  analysis_section(m, &x0_, &x1_);
  hist_bin_ = m.scene.pantograph_head.histogram_bin;
  hist_bins_ = std::max(1, static_cast<int>(std::ceil(m.scene.pantograph_head.horn_width / hist_bin_ - 1e-9)));
  hist_from_ = -0.5 * hist_bins_ * hist_bin_;
  contacts_.resize(m.collectors.size());
  if (m.lateral)
    for (ContactTrack& t : contacts_) t.histogram.assign(hist_bins_, 0.0);
  for (std::size_t c = 0; c < m.collectors.size(); ++c) {
    const std::string name = m.pantographs[m.collectors[c].pantograph].name +
                             (m.pantographs[m.collectors[c].pantograph].collectors.size() > 1 ? "_" + std::to_string(c) : "");
    columns_.push_back(name + "_station_m");
    columns_.push_back(name + "_lateral_m");
  }
  if (!m.lateral) return;
  const LateralModel& lat = *m.lateral;
  if (m.endless) {
    // The block's spans, each a contact wire's nodes from its support to the next; a block span
    // stands for the line's span at its station now (the block moves by whole spans: record()).
    // The line's spans are those the collectors pass over, from the rearmost one's start to the
    // front's end of the pass.
    endless_span_ = m.endless_span;
    first_line_span_ = static_cast<long>(
        std::floor((m.train_start + m.initial_line_offset + m.rear_collector_offset) / endless_span_ + 1e-9));
    const long last = static_cast<long>(std::ceil(m.train_end / endless_span_ - 1e-9));
    const std::size_t count = static_cast<std::size_t>(std::max(0L, last - first_line_span_));
    max_blow_off_.assign(count, 0.0);
    line_static_blow_off_.assign(count, std::nan(""));  // NaN: the span was never in the window
    for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) {
      const Wire& w = lat.wires[wi];
      if (!w.is_contact_wire) continue;
      for (std::size_t j = 0; j + 1 < w.support_nodes.size(); ++j) {
        const BlowOffRange r{static_cast<int>(wi), static_cast<int>(j), w.support_nodes[j], w.support_nodes[j + 1]};
        if (block_static_blow_off_.size() <= j) block_static_blow_off_.resize(j + 1, 0.0);
        for (int i = w.w_dof + r.begin; i < w.w_dof + r.end; ++i)
          block_static_blow_off_[j] = std::max(block_static_blow_off_[j], std::fabs(lat.initial[i] - lat.calm[i]));
        blow_off_ranges_.push_back(r);
      }
    }
    return;
  }
  max_blow_off_.assign(lat.spans, 0.0);
  for (std::size_t wi = 0; wi < lat.wires.size(); ++wi) {
    const int o = lat.wires[wi].w_dof, nn = lat.wires[wi].nodes();
    for (int i = 0; i < nn; ++i) {
      const int span = lat.node_span[o + i];
      if (span < 0) continue;
      if (blow_off_ranges_.empty() || blow_off_ranges_.back().wire != static_cast<int>(wi) ||
          blow_off_ranges_.back().span != span || blow_off_ranges_.back().end != i)
        blow_off_ranges_.push_back(BlowOffRange{static_cast<int>(wi), span, i, i});
      blow_off_ranges_.back().end = i + 1;
    }
  }
}

void LateralRecorder::record(const Model& m, const State& s) {
  if (!m.lateral) return;
  const LateralModel& lat = *m.lateral;
  for (std::size_t c = 0; c < m.collectors.size(); ++c) {
    const Collector& col = m.collectors[c];
    ContactTrack& t = contacts_[c];
    const double x = s.front + s.line_offset - m.pantographs[col.pantograph].position + col.offset;
    const double y = s.lateral.collector_lateral[c];
    const double f = s.collector_force(m, static_cast<int>(c));
    if (!(x < x0_ || x > x1_ || std::isnan(y))) {
      if (t.samples == 0) {
        t.min = std::numeric_limits<double>::infinity();
        t.max = -t.min;
      }
      ++t.samples;
      t.sum += y;
      t.sum2 += y * y;
      t.min = std::min(t.min, y);
      t.max = std::max(t.max, y);
      t.outside += std::fabs(y) > col.half_working_width;
      // (On one wire: at an overlap the running wire changes, and the point jumps between them.)
      if (t.any && !std::isnan(t.prev_y) && s.time > t.prev_t && s.lateral.collector_wire[c] == t.prev_wire) {
        const double v = std::fabs(y - t.prev_y) / (s.time - t.prev_t);
        t.sweep += v;
        t.sweep_max = std::max(t.sweep_max, v);
        ++t.sweeps;
      }
      if (f > 0.0) {
        ++t.contact_samples;
        const int b = static_cast<int>(std::floor((y - hist_from_) / hist_bin_));
        if (b >= 0 && b < hist_bins_) t.histogram[b] += 1.0;
      }
    }
    t.any = true;
    t.prev_t = s.time;
    t.prev_y = y;
    t.prev_wire = s.lateral.collector_wire[c];
    t.station = x;
    t.lateral = y;
  }
  if (s.time + 1e-12 >= next_blow_off_) {
    next_blow_off_ = s.time + kBlowOffPeriod;
    const bool windowed = lat.windowed && !s.lateral.window.empty();
    const double* y = s.lateral.y.data();
    const double* calm = lat.calm.data();
    // On an endless line, block span j is the line's span j + the spans the block has moved.
    const long moved = m.endless ? std::lround(s.line_offset / endless_span_) - first_line_span_ : 0;
    // Where the lateral plane is stepped: its window and, stepped on its own, the gust lead ahead
    // of it (LateralState::lead_y, at the lead's last step).
    const bool lead = lat.lead_every > 0 && !s.lateral.lead_window.empty();
    for (const BlowOffRange& r : blow_off_ranges_) {
      const long k = r.span + moved;
      if (k < 0 || k >= static_cast<long>(max_blow_off_.size())) continue;
      const int o = lat.wires[r.wire].w_dof;
      double most = max_blow_off_[k];
      bool seen = false;
      auto scan = [&](int b, int e, const double* at) {
        for (int i = o + b; i < o + e; ++i) {
          const double d = std::fabs(at[i] - calm[i]);
          most = d > most ? d : most;
        }
        seen |= b < e;
      };
      if (windowed) {
        scan(std::max(r.begin, s.lateral.window[r.wire].lo), std::min(r.end, s.lateral.window[r.wire].hi + 1), y);
        if (lead)
          scan(std::max(r.begin, s.lateral.lead_window[r.wire].lo), std::min(r.end, s.lateral.lead_window[r.wire].hi + 1),
               s.lateral.lead_y.data());
      } else {
        scan(r.begin, r.end, y);
      }
      if (!seen) continue;
      max_blow_off_[k] = most;
      if (m.endless) line_static_blow_off_[k] = block_static_blow_off_[r.span];
    }
  }
  // The samples run from the first recorded state: a recorder started after a reset that kept the
  // clock running samples at its rate from there, not every step until it reaches the clock.
  if (rows_.empty()) next_sample_ = s.time;
  if (sample_period_ > 0.0 && s.time + 1e-12 < next_sample_) return;
  next_sample_ += sample_period_;
  PassRecorder::Row r{s.time, {}};
  r.values.reserve(2 * m.collectors.size());
  for (std::size_t c = 0; c < m.collectors.size(); ++c) {
    r.values.push_back(contacts_[c].station);
    r.values.push_back(contacts_[c].lateral);
  }
  rows_.push_back(std::move(r));
  if (endless_ && rows_.size() > PassRecorder::kMaxRows) rows_.pop_front();
}

std::size_t LateralRecorder::memory_bytes() const {
  std::size_t b = 0;
  for (const PassRecorder::Row& r : rows_) b += sizeof(PassRecorder::Row) + r.values.capacity() * sizeof(double);
  for (const ContactTrack& t : contacts_) b += sizeof(ContactTrack) + t.histogram.capacity() * sizeof(double);
  b += (max_blow_off_.capacity() + block_static_blow_off_.capacity() + line_static_blow_off_.capacity()) * sizeof(double);
  b += blow_off_ranges_.capacity() * sizeof(BlowOffRange);
  return b;
}

LateralStatistics LateralRecorder::statistics(const Model& m, const State& s) const {
  LateralStatistics out;
  if (!m.lateral) return out;
  const LateralModel& lat = *m.lateral;
  for (std::size_t c = 0; c < m.collectors.size(); ++c) {
    const ContactTrack& t = contacts_[c];
    LateralContactStatistics st;
    st.pantograph = m.pantographs[m.collectors[c].pantograph].name;
    st.collector = static_cast<int>(c);
    st.bin = hist_bin_;
    st.from = hist_from_;
    st.histogram_percent = t.histogram;
    st.samples = t.samples;
    st.contact_samples = t.contact_samples;
    st.sweep_max = t.sweep_max;
    if (st.samples) {
      const double n = static_cast<double>(st.samples);
      st.min = t.min;
      st.max = t.max;
      st.mean = t.sum / n;
      st.std_dev = std::sqrt(std::max(0.0, t.sum2 / n - st.mean * st.mean));
      st.outside_working_percent = 100.0 * t.outside / n;
    } else {
      st.min = st.max = std::nan("");
    }
    if (t.sweeps) st.sweep_mean = t.sweep / t.sweeps;
    if (st.contact_samples)
      for (double& h : st.histogram_percent) h *= 100.0 / st.contact_samples;
    out.contacts.push_back(std::move(st));
  }
  const double limit = m.scene.wind && m.scene.wind->blow_off_limit ? *m.scene.wind->blow_off_limit
                                                                     : std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < max_blow_off_.size(); ++k) {
    SpanBlowOff b;
    if (m.endless) {
      if (std::isnan(line_static_blow_off_[k])) continue;  // (never reached by the window)
      b.span = static_cast<int>(first_line_span_ + static_cast<long>(k));
      b.start = b.span * endless_span_;
      b.end = b.start + endless_span_;
      b.static_m = line_static_blow_off_[k];
    } else {
      b.span = static_cast<int>(k);
      b.start = m.support_x[k];
      b.end = m.support_x[k + 1];
      b.static_m = lat.static_blow_off[k];
    }
    b.max_m = std::max(max_blow_off_[k], b.static_m);
    b.exceeded = b.max_m > limit;
    out.spans.push_back(b);
  }
  out.events = s.lateral.events;
  out.events_total = s.lateral.events_total;
  return out;
}

std::string lateral_coupling(const Model& m) {
  if (!m.lateral) return "";
  const LateralModel& lat = *m.lateral;
  std::string coupling;
  if (!lat.pendulums.empty())
    coupling = "two-way through the droppers: their tension sets the lateral pendulums, their lean's stretch "
               "(dy^2 - dy0^2) / (2 l) their vertical force";
  if (!lat.registrations.empty())
    coupling += std::string(coupling.empty() ? "" : "; ") +
                "two-way through the hinged steady arms: each registration is where its arm's end is, and the "
                "wire's lateral pull turns the arm";
  if (coupling.empty()) coupling = "to nothing: no dropper or hinged arm joins the planes, so the vertical pass is the 2-D line's";
  return coupling;
}

std::string lateral_statistics_json(const Model& m, const LateralStatistics& st) {
  using Json = nlohmann::json;
  Json j;
  if (!m.lateral) return "null";
  const LateralModel& lat = *m.lateral;
  const Scene& sc = m.scene;
  j["working_width_m"] = sc.pantograph_head.working_width;
  j["horn_width_m"] = sc.pantograph_head.horn_width;
  j["coupling"] = lateral_coupling(m);
  j["lateral_dofs"] = lat.n;
  j["lateral_substeps"] = lat.substeps;
  Json contacts = Json::array();
  for (const LateralContactStatistics& c : st.contacts) {
    Json cj;
    cj["pantograph"] = c.pantograph;
    cj["collector"] = c.collector;
    cj["samples"] = c.samples;
    cj["contact_samples"] = c.contact_samples;
    cj["mean_m"] = c.mean;
    cj["std_m"] = c.std_dev;
    cj["min_m"] = c.min;
    cj["max_m"] = c.max;
    cj["sweep_speed_mean_mps"] = c.sweep_mean;
    cj["sweep_speed_max_mps"] = c.sweep_max;
    cj["working_width_m"] = 2.0 * m.collectors[c.collector].half_working_width;
    cj["outside_working_width_percent"] = c.outside_working_percent;
    cj["histogram"] = {{"from_m", c.from}, {"bin_m", c.bin}, {"percent_of_contact_time", c.histogram_percent}};
    contacts.push_back(cj);
  }
  j["contact_points"] = contacts;
  Json spans = Json::array();
  for (const SpanBlowOff& b : st.spans)
    spans.push_back({{"span", b.span}, {"start_m", b.start}, {"end_m", b.end}, {"static_blow_off_m", b.static_m},
                     {"max_blow_off_m", b.max_m}, {"exceeded", b.exceeded}});
  j["blow_off"] = spans;
  if (sc.wind && sc.wind->blow_off_limit) {
    int exceeded = 0;
    for (const SpanBlowOff& b : st.spans) exceeded += b.exceeded;
    j["blow_off_limit_m"] = *sc.wind->blow_off_limit;
    j["blow_off_spans_exceeded"] = exceeded;
  }
  Json supports = Json::array();
  for (const LateralSupport& s : lat.supports)
    supports.push_back({{"wire", m.wires[s.wire].name}, {"station_m", s.x}, {"stagger_m", s.stagger}, {"anchor", s.anchor},
                        {"rigid", s.rigid}, {"pull_off_N", s.pull_off}, {"pull_off_mean_wind_N", s.pull_off_wind}});
  j["supports"] = supports;
  Json events = Json::array();
  for (const DewirementEvent& e : st.events)
    events.push_back({{"time_s", e.time}, {"station_m", e.station}, {"pantograph", m.pantographs[e.pantograph].name},
                      {"collector", e.collector}, {"lateral_m", e.lateral}});
  j["dewirements"] = events;
  j["dewirements_total"] = st.events_total;
  j["on_dewirement"] = sc.pantograph_head.on_dewirement == DewirementAction::kStop ? "stop" : "continue";
  return j.dump(2, ' ', false, Json::error_handler_t::replace);
}

}  // namespace catenary_sim
