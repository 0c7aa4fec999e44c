#include "catenary_sim/core/output/zero_phase_filter.hpp"

#include <algorithm>
#include <cmath>

namespace catenary_sim {
namespace {

struct Biquad {
  double b0, b1, b2, a1, a2;
};

// One pass of a biquad cascade (direct form II transposed), started in the steady state of the
// first sample so that the ends do not ring.
void run_cascade(const std::vector<Biquad>& cascade, std::vector<double>& x) {
  if (x.empty()) return;
  for (const Biquad& q : cascade) {
    const double x0 = x.front();
    double z2 = (q.b2 - q.a2) * x0;
    double z1 = (q.b1 - q.a1) * x0 + z2;
    for (double& xi : x) {
      const double in = xi;
      const double y = q.b0 * in + z1;
      z1 = q.b1 * in - q.a1 * y + z2;
      z2 = q.b2 * in - q.a2 * y;
      xi = y;
    }
  }
}

}  // namespace

std::vector<double> lowpass_zero_phase(const std::vector<double>& x, double fs, double fc) {
  const std::size_t n = x.size();
  if (n < 3 || fc >= 0.5 * fs) return x;
  // 4th-order Butterworth as two bilinear (pre-warped) sections with Q = 1/(2 cos(pi/8)) and
  // 1/(2 cos(3 pi/8)).
  std::vector<Biquad> cascade;
  const double w0 = 2.0 * M_PI * fc / fs, cw = std::cos(w0), sw = std::sin(w0);
  for (double q : {1.0 / (2.0 * std::cos(M_PI / 8.0)), 1.0 / (2.0 * std::cos(3.0 * M_PI / 8.0))}) {
    const double al = sw / (2.0 * q), a0 = 1.0 + al;
    cascade.push_back(Biquad{(1.0 - cw) / 2.0 / a0, (1.0 - cw) / a0, (1.0 - cw) / 2.0 / a0, -2.0 * cw / a0,
                             (1.0 - al) / a0});
  }
  // Odd reflection about each end over a few time constants of the filter.
  const std::size_t pad = std::min(n - 1, static_cast<std::size_t>(std::ceil(3.0 * fs / fc)));
  std::vector<double> y;
  y.reserve(n + 2 * pad);
  for (std::size_t i = pad; i >= 1; --i) y.push_back(2.0 * x.front() - x[i]);
  y.insert(y.end(), x.begin(), x.end());
  for (std::size_t i = 1; i <= pad; ++i) y.push_back(2.0 * x.back() - x[n - 1 - i]);
  run_cascade(cascade, y);
  std::reverse(y.begin(), y.end());
  run_cascade(cascade, y);
  std::reverse(y.begin(), y.end());
  return std::vector<double>(y.begin() + pad, y.begin() + pad + n);
}

}  // namespace catenary_sim
