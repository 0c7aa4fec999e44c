#include "catenary_sim/core/wind.hpp"

#include <unsupported/Eigen/FFT>

#include <algorithm>
#include <cmath>
#include <complex>
#include <random>

namespace catenary_sim {

double von_karman_spectrum(double f, double U, double sigma, double L) {
  if (!(f > 0.0)) return 0.0;
  const double n = f * L / U;
  return sigma * sigma * 4.0 * n / std::pow(1.0 + 70.8 * n * n, 5.0 / 6.0) / f;
}

void WindField::at_time(double t, double* out) const {
  const double period = samples * dt;
  double tau = std::fmod(t, period);
  if (tau < 0.0) tau += period;
  const double s = tau / dt;
  int n0 = static_cast<int>(s);
  if (n0 >= samples) n0 = samples - 1;
  const double b = s - n0;
  const int n1 = n0 + 1 == samples ? 0 : n0 + 1;
  const float* r0 = u.data() + static_cast<std::size_t>(n0) * points;
  const float* r1 = u.data() + static_cast<std::size_t>(n1) * points;
  for (int j = 0; j < points; ++j) out[j] = (1.0 - b) * r0[j] + b * r1[j];
}

WindField make_wind_field(const WindSpec& wind, double x_begin, double x_end, double duration) {
  WindField w;
  if (!wind.turbulence) return w;
  const TurbulenceSpec& t = *wind.turbulence;
  const double U = wind.speed, sigma = t.intensity * U;
  w.dx = t.spacing;
  w.x0 = x_begin;
  w.points = std::max(2, static_cast<int>(std::ceil((x_end - x_begin) / w.dx)) + 1);
  w.dt = 0.5 / t.max_frequency;
  int nt = 64;
  const double need = std::max(60.0, std::isfinite(duration) ? duration : 600.0);
  while (nt * w.dt < need && nt < (1 << 16)) nt *= 2;
  w.samples = nt;
  const int nf = nt / 2;  // frequencies k df, k = 1 .. nf - 1 (0 and Nyquist left out)
  const double df = 1.0 / (nt * w.dt);
  std::mt19937_64 gen(t.seed);
  // Uniform phase in [0, 2 pi) from 53 random bits (the same on every machine).
  auto phase = [&gen]() { return 2.0 * M_PI * static_cast<double>(gen() >> 11) * (1.0 / 9007199254740992.0); };
  // Coefficients per point, the autoregression running along the line for every frequency. The
  // phases are drawn point by point (all frequencies of point 0, then of point 1, ...), so that a
  // field over a longer stretch from the same first point, with the same time grid, extends a
  // shorter one: an endless line's field and a finite line's agree where both reach.
  std::vector<std::complex<double>> c(static_cast<std::size_t>(w.points) * (nf + 1), 0.0);
  std::vector<double> amplitude(nf, 0.0), rho(nf, 0.0), innovation(nf, 0.0);
  double var = 0.0;
  for (int k = 1; k < nf; ++k) {
    const double f = k * df;
    amplitude[k] = std::sqrt(2.0 * von_karman_spectrum(f, U, sigma, t.length_scale) * df);
    var += 0.5 * amplitude[k] * amplitude[k];
    rho[k] = std::exp(-t.coherence_decay * f * w.dx / U);
    innovation[k] = std::sqrt(1.0 - rho[k] * rho[k]);
  }
  for (int k = 1; k < nf; ++k) c[k] = std::polar(amplitude[k], phase());
  for (int j = 1; j < w.points; ++j) {
    const std::complex<double>* prev = c.data() + static_cast<std::size_t>(j - 1) * (nf + 1);
    std::complex<double>* cj = c.data() + static_cast<std::size_t>(j) * (nf + 1);
    for (int k = 1; k < nf; ++k) cj[k] = rho[k] * prev[k] + innovation[k] * std::polar(amplitude[k], phase());
  }
  w.sigma_target = std::sqrt(var);
  // Re sum_k c_k e^{i 2 pi k n / N}: Eigen's unscaled half-spectrum inverse gives
  // X_0 + 2 Re sum X_k e^{...}, so X_k = c_k / 2.
  Eigen::FFT<double> fft;
  fft.SetFlag(Eigen::FFT<double>::HalfSpectrum);
  fft.SetFlag(Eigen::FFT<double>::Unscaled);
  w.u.assign(static_cast<std::size_t>(nt) * w.points, 0.0f);
  std::vector<std::complex<double>> X(nf + 1);
  std::vector<double> series;
  for (int j = 0; j < w.points; ++j) {
    for (int k = 0; k <= nf; ++k) X[k] = 0.5 * c[static_cast<std::size_t>(j) * (nf + 1) + k];
    fft.inv(series, X, nt);
    for (int n = 0; n < nt; ++n) w.u[static_cast<std::size_t>(n) * w.points + j] = static_cast<float>(series[n]);
  }
  return w;
}

}  // namespace catenary_sim
