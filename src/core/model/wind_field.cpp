#include "catenary_sim/core/model/wind_field.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <random>

namespace catenary_sim {

namespace {

// The series' period covers the pass up to this (s): a point is in an endless line's block, or
// a finite pass lasts, longer only on slow or long passes, whose gusts then repeat at a point
// after the period; it bounds every point's series (16384 samples at the default 5 Hz).
constexpr double kLongestPeriod = 600.0;
constexpr int kMostSamples = 1 << 17;

double sample_time(const TurbulenceSpec& t) { return 0.25 / t.max_frequency; }

int sample_count(double dt, double duration) {
  const double need = std::max(60.0, std::min(std::isfinite(duration) ? duration : kLongestPeriod, kLongestPeriod));
  int nt = 64;
  while (nt * dt < need && nt < kMostSamples) nt *= 2;
  return nt;
}

// Points held for a stretch of `length` m: those around its ends, whatever its place on the grid.
double held_points(double length, double dx) { return std::ceil(length / dx) + 3.0; }

double sinc(double x) { return x == 0.0 ? 1.0 : std::sin(M_PI * x) / (M_PI * x); }

}  // namespace

double von_karman_spectrum(double f, double U, double sigma, double L) {
  if (!(f > 0.0)) return 0.0;
  const double n = f * L / U;
  return sigma * sigma * 4.0 * n / std::pow(1.0 + 70.8 * n * n, 5.0 / 6.0) / f;
}

std::size_t WindField::buffer_bytes() const {
  if (empty()) return 0;
  return static_cast<std::size_t>(samples) * held * sizeof(float) +
         static_cast<std::size_t>(2 * (samples / 2 + 1)) * sizeof(std::complex<double>) +
         static_cast<std::size_t>(samples) * sizeof(double);
}

double wind_field_bytes_estimate(const WindSpec& wind, double held_length) {
  if (!wind.turbulence) return 0.0;
  const TurbulenceSpec& t = *wind.turbulence;
  const double samples = sample_count(sample_time(t), kLongestPeriod);
  // The series, the coefficients and the FFT's input, its output, and its plan (about the size
  // of its input).
  return samples * held_points(held_length, t.spacing) * sizeof(float) + 3.0 * (samples / 2 + 1) * 16.0 + samples * 8.0;
}

WindField make_wind_field(const WindSpec& wind, double x_begin, double x_end, double duration, double held_length) {
  WindField w;
  if (!wind.turbulence) return w;
  const TurbulenceSpec& t = *wind.turbulence;
  const double U = wind.speed, sigma = t.intensity * U;
  w.dx = t.spacing;
  w.x0 = x_begin;
  w.points = std::max(2, static_cast<int>(std::ceil((x_end - x_begin) / w.dx)) + 1);
  w.held = static_cast<int>(std::min<double>(w.points, std::max(2.0, held_points(held_length, w.dx))));
  w.dt = sample_time(t);
  w.samples = sample_count(w.dt, duration);
  w.seed = t.seed;
  const double df = 1.0 / (w.samples * w.dt);
  // Frequencies k df up to max_frequency (below the grid's Nyquist frequency 2 max_frequency).
  w.frequencies = std::min(w.samples / 2, static_cast<int>(std::floor(t.max_frequency / df + 1e-9)) + 1);
  w.amplitude.assign(w.frequencies, 0.0);
  w.rho.assign(w.frequencies, 0.0);
  w.innovation.assign(w.frequencies, 0.0);
  double var = 0.0;
  for (int k = 1; k < w.frequencies; ++k) {
    const double f = k * df, target = std::sqrt(2.0 * von_karman_spectrum(f, U, sigma, t.length_scale) * df);
    var += 0.5 * target * target;
    // Linear interpolation between samples multiplies the amplitude at f by sinc^2(f dt): undone here.
    const double s = sinc(f * w.dt);
    w.amplitude[k] = target / (s * s);
    w.rho[k] = std::exp(-t.coherence_decay * f * w.dx / U);
    w.innovation[k] = std::sqrt(1.0 - w.rho[k] * w.rho[k]);
  }
  w.sigma_target = std::sqrt(var);
  return w;
}

void WindFieldBuffer::reset(const WindField& f) {
  first_ = end_ = 0;
  if (f.empty()) {
    u_.clear();
    return;
  }
  const int nf = f.samples / 2;
  u_.assign(static_cast<std::size_t>(f.samples) * f.held, 0.0f);
  c_.assign(nf + 1, 0.0);
  X_.assign(nf + 1, 0.0);
  series_.assign(f.samples, 0.0);
  gen_.seed(f.seed);
  fft_.fft = Eigen::FFT<double>();
  fft_.fft.SetFlag(Eigen::FFT<double>::HalfSpectrum);
  fft_.fft.SetFlag(Eigen::FFT<double>::Unscaled);
  fft_.samples = f.samples;
  extend_to(f, f.held - 1);  // (also makes the FFT's plan, so that later points allocate nothing)
}

void WindFieldBuffer::generate(const WindField& f) {
  // Uniform phase in [0, 2 pi) from 53 random bits (the same on every machine).
  auto phase = [this]() { return 2.0 * M_PI * static_cast<double>(gen_() >> 11) * (1.0 / 9007199254740992.0); };
  // The autoregression along the line for every frequency, the phases drawn point by point (all
  // frequencies of point 0, then of point 1, ...): a field over a longer stretch from the same
  // first point, with the same time grid, extends a shorter one.
  if (end_ == 0) {
    for (int k = 1; k < f.frequencies; ++k) c_[k] = std::polar(f.amplitude[k], phase());
  } else {
    for (int k = 1; k < f.frequencies; ++k)
      c_[k] = f.rho[k] * c_[k] + f.innovation[k] * std::polar(f.amplitude[k], phase());
  }
  // Re sum_k c_k e^{i 2 pi k n / N}: Eigen's unscaled half-spectrum inverse gives
  // X_0 + 2 Re sum X_k e^{...}, so X_k = c_k / 2.
  for (std::size_t k = 0; k < X_.size(); ++k) X_[k] = 0.5 * c_[k];
  fft_.fft.inv(series_.data(), X_.data(), f.samples);
  const std::size_t slot = static_cast<std::size_t>(end_ % f.held);
  for (int n = 0; n < f.samples; ++n) u_[static_cast<std::size_t>(n) * f.held + slot] = static_cast<float>(series_[n]);
  ++end_;
  first_ = std::max(first_, end_ - f.held);
}

void WindFieldBuffer::extend_to(const WindField& f, int last) {
  last = std::min(last, f.points - 1);
  while (end_ <= last) generate(f);
}

void WindFieldBuffer::at_time(const WindField& f, double t, double* out) const {
  const double period = f.samples * f.dt;
  double tau = std::fmod(t, period);
  if (tau < 0.0) tau += period;
  const double s = tau / f.dt;
  int n0 = static_cast<int>(s);
  if (n0 >= f.samples) n0 = f.samples - 1;
  const double b = s - n0;
  const int n1 = n0 + 1 == f.samples ? 0 : n0 + 1;
  const float* r0 = u_.data() + static_cast<std::size_t>(n0) * f.held;
  const float* r1 = u_.data() + static_cast<std::size_t>(n1) * f.held;
  // The ring from first's slot to its end, then from its start.
  const int count = end_ - first_, s0 = first_ % f.held, head = std::min(count, f.held - s0);
  for (int i = 0; i < head; ++i) out[i] = (1.0 - b) * r0[s0 + i] + b * r1[s0 + i];
  for (int i = head; i < count; ++i) out[i] = (1.0 - b) * r0[i - head] + b * r1[i - head];
}

std::size_t WindFieldBuffer::bytes() const {
  return u_.capacity() * sizeof(float) + (c_.capacity() + X_.capacity()) * sizeof(std::complex<double>) +
         series_.capacity() * sizeof(double);
}

}  // namespace catenary_sim
