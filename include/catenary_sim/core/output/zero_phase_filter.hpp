// The low-pass filter of EN 50317 / EN 50318 contact-force statistics, without phase lag.
#pragma once

#include <vector>

namespace catenary_sim {

// Zero-phase low-pass: a 4th-order Butterworth run forward and backward (filtfilt), with odd
// reflection padding at both ends. fs and fc in Hz.
std::vector<double> lowpass_zero_phase(const std::vector<double>& x, double fs, double fc);

}  // namespace catenary_sim
