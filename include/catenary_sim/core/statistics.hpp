// Pass statistics as EN 50318 / EN 50317 use them: contact force low-pass filtered (zero phase),
// over an analysis section, per pantograph.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "catenary_sim/core/model.hpp"
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

struct PantographStatistics {
  std::string name;
  std::vector<WireContactStatistics> wires;  // per contact wire of the line
  ForceStatistics filtered;    // contact force low-pass filtered at the cutoff (zero phase)
  ForceStatistics unfiltered;  // as computed, at every step
  double contact_loss_percent = 0.0;   // share of steps in the section with zero total force
  double max_uplift_at_support_m = 0.0;  // largest steady-arm uplift in the section (NaN: no steady arms)
  std::size_t samples = 0;
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
std::string statistics_json(const Model& model, const State& state, const std::vector<PantographStatistics>& stats,
                            const RunInfo& run);

// Records one pass at every step and reduces it to statistics and a decimated time series.
class PassRecorder {
 public:
  PassRecorder(const Model& model, double sample_rate_hz = 0.0);
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
};

}  // namespace catenary_sim
