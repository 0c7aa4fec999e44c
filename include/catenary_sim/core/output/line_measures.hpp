// What line engineers measure, as pure functions of recorded series (no Model, no State): contact
// losses as arcing events, rainflow counting for dropper fatigue, the Welch power spectral density
// and its peaks. PassRecorder (pass_recorder.hpp) feeds them; simulate_pass and scripts/pass_report
// write and draw what they return.
#pragma once

#include <cstddef>
#include <vector>

namespace catenary_sim {

// ---- Contact loss (arcing) events ----------------------------------------------------------

// One contact loss: a maximal run of consecutive samples with force <= 0.
struct ContactLossEvent {
  double start_time = 0.0;  // s, time of the first sample without force
  double station = 0.0;     // m, position of the pantograph at that sample
  double duration = 0.0;    // s, from the first sample without force to the first with force again
  double length = 0.0;      // m, travelled during the loss
};

// Contact losses in a series sampled at times t (increasing) and positions x, counted only where
// x lies in [x0, x1] (a loss crossing a bound is cut there). A loss still running at the last
// sample in the section ends one sample period after it (the sample stands for its period).
std::vector<ContactLossEvent> contact_loss_events(const std::vector<double>& t, const std::vector<double>& x,
                                                  const std::vector<double>& force, double x0, double x1);

// ---- Rainflow counting (ASTM E1049-85 (2017), section 5.4.4) -------------------------------

// Reversals (peaks and valleys) of a series, built one sample at a time: a sample that continues
// the current direction replaces the last reversal, a repeated value is dropped. Run on every step
// of a pass for each dropper, so the reversal still moving is held here and the list is written
// only when the direction turns (one comparison a sample, a push a reversal).
class TurningPoints {
 public:
  // Inline: a pass adds every analysed dropper's force at every step.
  void add(double v) {
    if (!started_) {
      last_ = v;
      started_ = true;
      return;
    }
    if (v == last_) return;
    const int dir = v > last_ ? 1 : -1;
    if (dir != direction_) {
      points_.push_back(last_);  // the direction turned: the last reversal is final
      direction_ = dir;
    }
    last_ = v;  // still rising (falling): the reversal moves on
  }
  std::vector<double> points() const;  // the reversals so far, the one still moving last
  bool empty() const { return !started_; }
  std::size_t capacity() const { return points_.capacity(); }

 private:
  std::vector<double> points_;  // the reversals before the last
  double last_ = 0.0;           // the last reversal (moves on while the direction holds)
  bool started_ = false;
  int direction_ = 0;  // +1 rising, -1 falling, 0 not yet known
};

std::vector<double> turning_points(const std::vector<double>& x);

struct RainflowCycle {
  double range = 0.0;  // peak-to-valley
  double mean = 0.0;
  double count = 0.0;  // 1 (full cycle) or 0.5 (half cycle)
};

// Rainflow counting of a series of reversals (turning_points() first if it is a raw series),
// ASTM E1049-85 5.4.4 (three-point method with the starting point moving on as half cycles are
// counted); the ranges left at the end count as half cycles.
std::vector<RainflowCycle> rainflow(const std::vector<double>& reversals);

// Cycle counts in `bins` equal ranges over [0, max_range]; a range equal to max_range goes into
// the last bin, larger ones are left out. Returns the counts (bin i: [i, i+1) * max_range / bins).
std::vector<double> rainflow_histogram(const std::vector<RainflowCycle>& cycles, double max_range, int bins);

// ---- Power spectral density (Welch) ---------------------------------------------------------

struct Spectrum {
  std::vector<double> frequency;  // Hz, 0 .. fs/2 in steps of fs / nfft
  std::vector<double> psd;        // unit^2 / Hz, one-sided
  double resolution = 0.0;        // Hz, fs / segment length (the Hann main lobe is 4 of these wide)
  std::size_t segment = 0, segments = 0;
};

// Welch's method as scipy.signal.welch(x, fs, window='hann', nperseg=segment, noverlap=segment/2,
// nfft=next power of two >= segment, detrend='constant', scaling='density'): the mean of the
// periodic-Hann-windowed periodograms of half-overlapping segments. segment is clamped to the
// series length. The integral of psd over frequency is the variance of x.
Spectrum welch_psd(const std::vector<double>& x, double fs, std::size_t segment);

struct SpectralPeak {
  double frequency = 0.0;  // Hz
  double psd = 0.0;        // unit^2 / Hz at the peak
  double amplitude = 0.0;  // unit: sqrt(2 x power within +-3 resolutions), a sine's amplitude
};

// The strongest local maxima of the PSD in [f_lo, f_hi], strongest first, at most `count`, no two
// closer than 4 resolutions (one Hann main lobe).
std::vector<SpectralPeak> spectral_peaks(const Spectrum& s, double f_lo, double f_hi, std::size_t count);

}  // namespace catenary_sim
