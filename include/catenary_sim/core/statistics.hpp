// Pass statistics as EN 50318 / EN 50317 use them: contact force low-pass filtered (zero phase),
// over an analysis section, per pantograph.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "catenary_sim/core/model.hpp"
#include "catenary_sim/core/outputs.hpp"
#include "catenary_sim/core/state.hpp"

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

// The contact-force spectrum over the analysis section (Welch, outputs.hpp) with the frequencies
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
  std::vector<ContactLossEvent> loss_events;  // in the section, at every step
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
class PassRecorder {
 public:
  PassRecorder(const Model& model, double sample_rate_hz = 0.0);
  // record_droppers false: no per-dropper recording (for the cost comparison of the benchmark).
  PassRecorder(const Model& model, double sample_rate_hz, bool record_droppers);
  // The initial state, then the state after each successful step().
  void record(const Model& model, const State& state);
  std::vector<PantographStatistics> statistics(const Model& model) const;
  // The same with another low-pass cutoff (Hz), e.g. 200 Hz for the extremes of EN 50317.
  std::vector<PantographStatistics> statistics(const Model& model, double cutoff_hz) const;

  // Time series at the output sample rate (every step when 0).
  struct Row {
    double time;
    std::vector<double> values;
  };
  std::vector<std::string> columns() const { return columns_; }
  const std::vector<Row>& rows() const { return rows_; }

  // Droppers, steady arms, over the pass.
  LineStatistics line_statistics(const Model& model) const;
  // The largest uplift so far (m, every step while a pantograph was within half a span) of the
  // steady arm at `station` m along the line (s.line_offset included); NaN if none was recorded.
  double max_steady_arm_uplift(double station) const;
  // Contact-force PSD per pantograph over the analysis section (unfiltered, every step).
  std::vector<Spectrum> spectra(const Model& model) const;
  // At the times of rows(): per pantograph its position, the contact force filtered at the
  // statistics' cutoff and the measuring pantograph's force (NaN without a head).
  std::vector<std::string> processed_columns() const;
  std::vector<Row> processed_rows(const Model& model) const;
  // output.dropper_series: the analysed droppers' forces at the times of rows().
  std::vector<std::string> dropper_columns() const;
  const std::vector<Row>& dropper_rows() const { return dropper_rows_; }

 private:
  double sample_period_;
  double next_sample_ = 0.0;
  std::vector<std::string> columns_;
  std::vector<Row> rows_;
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
  std::vector<Row> dropper_rows_;
  std::vector<double> measured_force(const Model& model, std::size_t p) const;
  void measured_statistics(const Model& model, std::size_t p, double x0, double x1, const std::vector<double>& filtered,
                           MeasuredForceStatistics* out) const;
  SpectrumSummary spectrum_summary(const Model& model, std::size_t p, const Spectrum& s) const;
  Spectrum spectrum(const Model& model, std::size_t p) const;
};

}  // namespace catenary_sim
