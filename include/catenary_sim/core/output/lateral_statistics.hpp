// What the 3-D line reports (docs/offline_runs.md): where the contact point runs across the
// strips (a histogram, the wear distribution, and the sweep speed), the wires' blow-off per span
// against wind.blow_off_limit, the supports' pull-off forces and the dewirement events.
#pragma once

#include <deque>
#include <string>
#include <vector>

#include "catenary_sim/core/model/lateral.hpp"
#include "catenary_sim/core/engine/state.hpp"
#include "catenary_sim/core/output/pass_recorder.hpp"

namespace catenary_sim {

// One collector over the analysis section.
struct LateralContactStatistics {
  std::string pantograph;
  int collector = 0;
  std::size_t samples = 0, contact_samples = 0;  // steps in the section; those with contact force
  double mean = 0.0, std_dev = 0.0, min = 0.0, max = 0.0;  // m across the strip (+ left)
  double sweep_mean = 0.0, sweep_max = 0.0;  // m/s, |d(lateral)/dt| (the rate the contact point crosses the strip),
                                             // on one wire (a hand-over to another wire is a jump, not a sweep)
  // Share (%) of the contact time (steps with contact force) per bin of width `bin` from `from`,
  // over the head's horn width: the strips' wear distribution.
  double from = 0.0, bin = 0.0;
  std::vector<double> histogram_percent;
  double outside_working_percent = 0.0;  // share of the steps in the section beyond the working width
};

struct SpanBlowOff {
  int span = 0;
  double start = 0.0, end = 0.0;  // m
  double static_m = 0.0;  // m, under the mean wind (largest |y - calm| on the contact wire)
  double max_m = 0.0;     // m, over the pass (turbulence included), sampled every 5 ms; on an
                          // endless line while the span is in the lateral window (gust lead included)
  bool exceeded = false;  // max_m above wind.blow_off_limit
};

struct LateralStatistics {
  std::vector<LateralContactStatistics> contacts;
  std::vector<SpanBlowOff> spans;
  std::vector<DewirementEvent> events;
  std::int64_t events_total = 0;
};

class LateralRecorder {
 public:
  LateralRecorder(const Model& model, double sample_rate_hz = 0.0);
  // The initial state, then the state after each successful step().
  void record(const Model& model, const State& state);
  LateralStatistics statistics(const Model& model, const State& state) const;
  // Time series at the output sample rate: per collector its station and lateral position.
  // (On an endless line the last PassRecorder::kMaxRows.)
  std::vector<std::string> columns() const { return columns_; }
  const std::deque<PassRecorder::Row>& rows() const { return rows_; }
  // Bytes held for the pass: the rows and the blow-off per span; the contact point's statistics
  // are running sums (exactly the sums over the recorded steps, in their order).
  std::size_t memory_bytes() const;

 private:
  double sample_period_ = 0.0, next_sample_ = 0.0, next_blow_off_ = 0.0;
  bool endless_ = false;
  std::vector<std::string> columns_;
  std::deque<PassRecorder::Row> rows_;
  // Per collector over the analysis section, as the steps come.
  struct ContactTrack {
    std::size_t samples = 0, contact_samples = 0, outside = 0, sweeps = 0;
    double sum = 0.0, sum2 = 0.0, sweep = 0.0, sweep_max = 0.0, min = 0.0, max = 0.0;
    std::vector<double> histogram;  // steps with contact per bin
    bool any = false;               // a step recorded (prev_* valid)
    double prev_t = 0.0, prev_y = 0.0, station = 0.0, lateral = 0.0;  // the last step's
    int prev_wire = -1;
  };
  std::vector<ContactTrack> contacts_;
  double x0_ = 0.0, x1_ = 0.0, hist_from_ = 0.0, hist_bin_ = 0.0;
  int hist_bins_ = 0;
  std::vector<double> max_blow_off_;                   // per span (of the line's spans the pass covers, when endless)
  // Endless line: the span length, the first line span reported, the static blow-off per block
  // span, and per line span the one of the block span it was last recorded on (NaN: never).
  double endless_span_ = 0.0;
  long first_line_span_ = 0;
  std::vector<double> block_static_blow_off_, line_static_blow_off_;
  // The contact wires' nodes by span (node ranges [begin, end) of lateral wire `wire`), scanned for
  // the blow-off every kBlowOffPeriod: a max over each range, within the window if there is one
  // (outside it the wires are in the static state, whose blow-off the statistics take anyway).
  struct BlowOffRange {
    int wire = 0, span = 0, begin = 0, end = 0;
  };
  std::vector<BlowOffRange> blow_off_ranges_;
};

// The "lateral" object of stats.json (JSON text).
std::string lateral_statistics_json(const Model& model, const LateralStatistics& stats);

// What joins a 3-D line's two planes, in words (stats.json's lateral.coupling, the summaries):
// the droppers, the hinged steady arms, or nothing. "" on a 2-D line.
std::string lateral_coupling(const Model& model);

}  // namespace catenary_sim
