// Pass statistics as EN 50318 / EN 50317 use them: contact force low-pass filtered (zero phase),
// over an analysis section, per pantograph.
#pragma once

#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/output/line_measures.hpp"
#include "catenary_sim/core/engine/state.hpp"

namespace catenary_sim {

struct ForceStatistics {
  double mean = 0.0, std_dev = 0.0, max = 0.0, min = 0.0;  // N
  double stat_max = 0.0, stat_min = 0.0;                   // N, mean +- 3 std_dev
};

// The share of one contact wire in a pantograph's contact (over all its collectors).
struct WireContactStatistics {
  std::string wire;
  double mean_force = 0.0, max_force = 0.0;  // N, unfiltered, over the section
  double contact_percent = 0.0;              // share of steps with force on this wire
};

// The contact-force spectrum over the analysis section (Welch, line_measures.hpp) with the frequencies
// at which the train passes spans and droppers.
struct SpectrumSummary {
  double span_passing_hz = 0.0;     // v / mean span of the section
  double dropper_passing_hz = 0.0;  // v / median dropper spacing within a span (NaN: no droppers)
  double resolution_hz = 0.0, segment_s = 0.0;
  std::size_t segments = 0;
  std::vector<SpectralPeak> peaks;  // strongest first, 2 resolutions .. kSpectrumMaxHz
};
constexpr double kSpectrumMaxHz = 200.0;  // spectra are written and searched up to this

// What a measuring pantograph would report (docs/offline_runs.md): the head suspension's spring
// and damper force minus head mass x head acceleration, low-passed (zero phase) at the sensor
// bandwidth, against the true contact force low-passed at the statistics' cutoff.
struct MeasuredForceStatistics {
  bool available = false;  // false for a moving force or an external pantograph (no head)
  double bandwidth_hz = 0.0;
  ForceStatistics force;
  double rms_difference = 0.0, max_abs_difference = 0.0;  // N, measured - true filtered
};

struct PantographStatistics {
  std::string name;
  std::vector<WireContactStatistics> wires;  // per contact wire of the line
  ForceStatistics filtered;    // contact force low-pass filtered at the cutoff (zero phase)
  ForceStatistics unfiltered;  // as computed, at every step
  double contact_loss_percent = 0.0;   // share of steps in the section with zero total force
  double max_uplift_at_support_m = 0.0;  // largest steady-arm uplift in the section (NaN: no steady arms)
  std::size_t samples = 0;
  std::vector<ContactLossEvent> loss_events;  // in the section, at every step (endless: the first kMaxListed)
  std::size_t loss_events_total = 0;          // all of them (loss_events.size() on a finite line)
  double loss_events_per_km = 0.0, longest_loss_s = 0.0;
  SpectrumSummary spectrum;
  MeasuredForceStatistics measured;
  // The scene's target mean force Fm(v) = a v^2 + b (pantographs[].target_mean_force) at the
  // train's mean speed through the section: present only when the scene gives one.
  struct TargetMean {
    double speed_mps = 0.0;   // mean speed through the section
    double target = 0.0;      // N, Fm(speed)
    double difference = 0.0;  // N, filtered mean - target
    std::optional<double> tolerance;  // N, from the scene
    bool within = true;       // |difference| <= tolerance (true without a tolerance)
  };
  std::optional<TargetMean> target_mean;
};

// One dropper of the analysis section over the whole pass: its force (elastic tension, 0 when
// slack, as the integrator decides) and its rainflow-counted ranges.
struct DropperStatistics {
  double station = 0.0;  // m
  int span = 0;          // span index along the line
  double static_tension = 0.0, max_force = 0.0, min_force = 0.0;  // N
  double slack_percent = 0.0;  // share of steps slack
  double cycles = 0.0;         // rainflow cycles counted (a half cycle as 0.5)
  double max_range = 0.0;      // N, largest counted range
  std::vector<double> histogram;  // cycles per range bin (LineStatistics::range_bin_n wide)
};

struct SteadyArmStatistics {
  double station = 0.0;     // m
  double max_uplift = 0.0;  // m, largest over the pass and all pantographs
  bool exceeded = false;    // above output.allowed_uplift
};

struct LineStatistics {
  std::vector<DropperStatistics> droppers;  // those in the analysis section (none on an endless line)
  double range_bin_n = 0.0;                 // N, width of the rainflow histogram bins
  std::vector<SteadyArmStatistics> steady_arms;  // in the analysis section
};

// Zero-phase low-pass: a 4th-order Butterworth run forward and backward (filtfilt), with odd
// reflection padding at both ends. fs and fc in Hz.
std::vector<double> lowpass_zero_phase(const std::vector<double>& x, double fs, double fc);

ForceStatistics force_statistics(const std::vector<double>& x);

// How a pass ran, for the report (NaN / negative: left out).
struct RunInfo {
  double wall_time_s = 0.0;
  double build_time_s = -1.0;
  long long overruns = -1;
};

// The pass report as JSON (stats.json of simulate_pass, ~stats_file of the node): run figures and
// per pantograph the filtered and unfiltered force statistics.
// With `line`, also the droppers, the steady arms against output.allowed_uplift, the stations of
// supports and droppers and the scene's limits with pass/fail marks.
std::string statistics_json(const Model& model, const State& state, const std::vector<PantographStatistics>& stats,
                            const RunInfo& run, const LineStatistics* line = nullptr);

// Records one pass at every step and reduces it to statistics and a decimated time series.
//
// A finite line's pass is kept whole (every step, per pantograph: a few doubles) and reduced at the
// end: its length bounds it, and the zero-phase filter then sees the whole record.
//
// An endless line's pass has no end to wait for (a live node runs for days), so its recorder keeps
// bounded memory and statistics() a bounded cost (docs/offline_runs.md, "Endless passes"):
// - running since the start of the pass: the filtered and unfiltered force's mean, std, min, max
//   (and mean +- 3 std), contact loss share, per contact wire figures, the measuring pantograph's,
//   the largest steady-arm uplift, the loss events' count, rate and longest; the zero-phase filter
//   runs on blocks with kFilterSettling/cutoff seconds of overlap on each side, past which the
//   4th-order Butterworth's slowest pole (decay 2 pi fc sin(pi/8)) has decayed to 2e-17: the
//   filtered force is the whole-record filtfilt's to rounding;
// - windowed: the spectrum over the last kSpectrumWindow s in the section (and the filtered
//   statistics at a cutoff other than output.filter_cutoff); the time series (rows(),
//   processed_rows()) the last kMaxRows rows; of the loss events the first kMaxListed listed, of
//   the steady arms the last kMaxListed.
// memory_bytes() reports what it holds.
class PassRecorder {
 public:
  static constexpr double kFilterSettling = 16.0;   // filter time constants of overlap, in 1/fc
  // s of force kept for an endless pass's spectrum: about 45 eight-span segments at 300 km/h, and
  // the 100 spans of config/reference_55m_endless.yaml whole
  static constexpr double kSpectrumWindow = 120.0;
  static constexpr std::size_t kMaxRows = 1u << 18;  // time series rows kept on an endless line
  static constexpr std::size_t kMaxListed = 1000;   // loss events and steady arms listed (endless)

  PassRecorder(const Model& model, double sample_rate_hz = 0.0);
  // record_droppers false: no per-dropper recording (for the cost comparison of the benchmark).
  PassRecorder(const Model& model, double sample_rate_hz, bool record_droppers);
  // The initial state, then the state after each successful step().
  void record(const Model& model, const State& state);
  std::vector<PantographStatistics> statistics(const Model& model) const;
  // The same with another low-pass cutoff (Hz), e.g. 200 Hz for the extremes of EN 50317 (on an
  // endless line over the spectrum's window: only the scene's cutoff is filtered as the pass runs).
  std::vector<PantographStatistics> statistics(const Model& model, double cutoff_hz) const;

  // Time series at the output sample rate (every step when 0).
  struct Row {
    double time;
    std::vector<double> values;
  };
  std::vector<std::string> columns() const { return columns_; }
  const std::deque<Row>& rows() const { return rows_; }
  // True on an endless line: running and windowed statistics in bounded memory (above).
  bool running() const { return running_; }
  // Bytes the recorder holds for the pass (its buffers' capacities): grows with a finite pass,
  // bounded on an endless one.
  std::size_t memory_bytes() const;

  // Droppers, steady arms, over the pass.
  LineStatistics line_statistics(const Model& model) const;
  // The largest uplift so far (m, every step while a pantograph was within half a span) of the
  // steady arm at `station` m along the line (s.line_offset included); NaN if none was recorded.
  double max_steady_arm_uplift(double station) const;
  // Contact-force PSD per pantograph over the analysis section (unfiltered, every step).
  std::vector<Spectrum> spectra(const Model& model) const;
  // At the times of rows(): per pantograph its position, the contact force filtered at the
  // statistics' cutoff and the measuring pantograph's force (a moving force: the force it applies;
  // no value before a pass has three steps).
  std::vector<std::string> processed_columns() const;
  std::deque<Row> processed_rows(const Model& model) const;
  // output.dropper_series: the analysed droppers' forces at the times of rows().
  std::vector<std::string> dropper_columns() const;
  const std::deque<Row>& dropper_rows() const { return dropper_rows_; }

 private:
  double sample_period_;
  double next_sample_ = 0.0;
  bool running_ = false;
  std::vector<std::string> columns_;
  std::deque<Row> rows_;
  std::vector<double> time_;
  std::vector<std::vector<double>> position_, force_;  // per pantograph, every step
  std::vector<std::vector<std::vector<double>>> wire_force_;  // per pantograph, per contact wire, every step
  std::vector<int> steady_arm_springs_;                 // indices into model.springs, in line order
  std::vector<double> steady_arm_x_;                    // m, their stations
  double longest_span_ = 0.0;                           // m
  std::vector<std::map<long long, double>> max_uplift_;  // per pantograph: steady arm station (mm) -> max uplift (m)
  std::vector<std::string> names_;                       // pantographs
  std::vector<std::size_t> row_index_;                   // step index of each row
  // Measuring pantograph, per pantograph at every step: head displacement, stretch of the head
  // suspension (mass below minus head) and its elastic force plus the uplift when it acts on the head.
  std::vector<std::vector<double>> head_u_, suspension_stretch_, suspension_force_;
  // Droppers of the analysis section.
  struct DropperTrack {
    int index = 0;
    double station = 0.0;
    double max = -1e300, min = 1e300;
    std::size_t slack = 0;
    TurningPoints reversals;
  };
  std::vector<DropperTrack> droppers_;
  std::size_t steps_ = 0;
  std::deque<Row> dropper_rows_;

  // ---- An endless pass: running statistics (above) ----
  struct Moments {  // Welford's running mean and variance, with min and max
    std::size_t n = 0;
    double mean = 0.0, m2 = 0.0, min = 0.0, max = 0.0;
    void add(double v);
    ForceStatistics statistics() const;
  };
  struct Running {  // one pantograph's
    Moments filtered, unfiltered, measured;
    std::size_t lost = 0;
    double diff_sq = 0.0, diff_max = 0.0;  // measured - true filtered
    std::vector<double> wire_sum, wire_max;
    std::vector<std::size_t> wire_on;
    // Contact loss events as contact_loss_events() finds them, one step at a time.
    bool open = false;
    ContactLossEvent event;
    std::size_t events = 0;
    double longest = 0.0;
    std::vector<ContactLossEvent> listed;  // the first kMaxListed
    bool any_in = false;                   // a step in the section seen
    double in_t = 0.0, in_x = 0.0, in_dt = 0.0, in_dx = 0.0;  // the last such step, and its step
    double first_t = 0.0, first_x = 0.0;   // the first such step (the section's mean speed)
    double uplift = -1e300;                // largest steady-arm uplift in the section
    std::deque<double> window;             // the unfiltered force in the section, last kSpectrumWindow s
  };
  // Steps [first_, first_ + time.size()) buffered for the zero-phase filter; [0, committed_) are
  // in the running statistics. `measured` lags one step (its central differences need the next).
  struct Buffer {
    std::vector<double> time;
    std::vector<std::vector<double>> x, force, measured;  // per pantograph
  };
  std::vector<Running> run_;
  Buffer buf_;
  std::size_t first_ = 0, committed_ = 0, margin_ = 0, block_ = 0, window_steps_ = 0;
  double x0_ = 0.0, x1_ = 0.0;  // the analysis section
  std::deque<std::size_t> pending_rows_;  // steps of rows whose processed values are not known yet
  std::deque<Row> processed_;             // processed rows of the committed steps
  std::vector<std::vector<double>> head_history_;  // per pantograph: u, stretch, force per head of the last 3 steps
  std::map<long long, double> arms_;     // steady arm station (mm) -> largest uplift, the last kMaxListed
  void record_whole(const Model& model, const State& state);
  void record_running(const Model& model, const State& state);
  // Reduces buffered steps [committed_, end) into `run` (and `processed`), the buffer's right end
  // being the record's end (`final`) or a margin before it.
  void commit(const Model& model, std::size_t end, bool final, std::vector<Running>* run, std::deque<Row>* processed,
              std::deque<std::size_t>* pending) const;
  std::vector<PantographStatistics> running_statistics(const Model& model, double cutoff_hz) const;
  std::vector<double> measured_force(const Model& model, std::size_t p) const;
  void measured_statistics(const Model& model, std::size_t p, double x0, double x1, const std::vector<double>& filtered,
                           MeasuredForceStatistics* out) const;
  SpectrumSummary spectrum_summary(const Model& model, double speed, const Spectrum& s) const;
  Spectrum spectrum(const Model& model, std::size_t p) const;
};

}  // namespace catenary_sim
