// The recorder of a pass: every step in, the pass's figures (force_statistics.hpp) and its time
// series out.
#pragma once

#include <deque>
#include <map>
#include <string>
#include <vector>

#include "catenary_sim/core/engine/state.hpp"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/output/force_statistics.hpp"
#include "catenary_sim/core/output/line_measures.hpp"

namespace catenary_sim {

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
    int messenger_dof = 0, contact_dof = 0;  // the model's dropper's, read at every step
    double static_tension = 0.0, stiffness = 0.0;
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
  // The endless line's members (Moments, Running and the functions down to running_statistics) are
  // defined in pass_recorder_endless.cpp, the rest in pass_recorder.cpp.
  void record_running(const Model& model, const State& state);
  void record_head(const Model& model, const State& state, std::size_t p);
  void record_in_section(const Model& model, const State& state, std::size_t p, double x, double force, double dt,
                         double dx);
  void record_steady_arms(const Model& model, const State& state, double model_station, Running* run);
  void settle_block(const Model& model);
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
