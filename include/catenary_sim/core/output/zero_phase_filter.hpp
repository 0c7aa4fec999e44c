// The low-pass filter of EN 50317 / EN 50318 contact-force statistics, without phase lag.
#pragma once

#include <vector>

namespace catenary_sim {

// The lowest cutoff (Hz) the statistics' filter takes: its settling, about 1 / fc, is then 10 s, a
// pass's length; far below it the filter, started at rest on a record shorter than its memory,
// returns its own start (at 1e-300 Hz a force of 0 N throughout), not the record's
// low-frequency content. The standards' cutoff is 20 Hz; the span-passing frequency above 1 Hz.
constexpr double kLeastFilterCutoff = 0.1;

// Zero-phase low-pass: a 4th-order Butterworth run forward and backward (filtfilt), with odd
// reflection padding at both ends. fs and fc in Hz.
std::vector<double> lowpass_zero_phase(const std::vector<double>& x, double fs, double fc);

}  // namespace catenary_sim
