// The figures of a pass as EN 50318 / EN 50317 use them: contact force low-pass filtered (zero
// phase), over an analysis section, per pantograph; the droppers' and steady arms' over the line.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "catenary_sim/core/output/line_measures.hpp"
#include "catenary_sim/core/scene/scene.hpp"

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
// slack, as the integrator decides; a dropper at the step's middle, the tension it acted with) and
// its rainflow-counted ranges.
struct DropperStatistics {
  double station = 0.0;  // m
  int span = 0;          // span index along the line
  bool hanger = false;   // a compound line's hanger (auxiliary messenger to contact wire)
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
  // A hinged arm (HingedArmSpec; false: a spring of eq. 4): its k_A, its inclination below the
  // hinge at the assembly and with the tip at the largest uplift (rad; negative: above the hinge).
  bool hinged = false;
  double stiffness = 0.0;  // N/m
  double pull_off = 0.0;   // N
  double inclination = 0.0, inclination_at_max_uplift = 0.0;
  // m, the arm's end's sideways travel at the largest uplift, a (cos(theta) - cos(theta0)), out
  // toward the wire's pull: on a 3-D line the lateral plane moves the registration point by it.
  double registration_travel = 0.0;
};

struct LineStatistics {
  std::vector<DropperStatistics> droppers;  // those in the analysis section (none on an endless line)
  double range_bin_n = 0.0;                 // N, width of the rainflow histogram bins
  std::vector<SteadyArmStatistics> steady_arms;  // in the analysis section
};

ForceStatistics force_statistics(const std::vector<double>& x);

// The standards' permissible mean force Fm(v) (`target`, the scene's
// pantographs[].target_mean_force) against the pass's filtered `mean` force, at the section's mean
// speed v (m/s); none without a target or with no mean.
std::optional<PantographStatistics::TargetMean> target_mean(const std::optional<TargetMeanForce>& target, double v,
                                                            double mean);

}  // namespace catenary_sim
