// Wind on the wires (the loads' room, not the integrator's): the mean speed, and a seeded
// along-wind turbulent field u'(x, t) along the line.
//
// Spectrum: von Karman's along-wind spectrum (von Karman 1948; ESDU 85020),
//   f S_u(f) / sigma_u^2 = 4 n / (1 + 70.8 n^2)^(5/6),  n = f L_u / U,
// one-sided in f, with sigma_u = intensity x U. Spatial coherence along the line: Davenport's
// (1961) exponential coherence coh(dx, f) = exp(-C f dx / U), taken as the normalised
// cross-spectrum (real, no phase).
// Generation: spectral representation (Shinozuka & Deodatis 1991) on equally spaced points. For
// the exponential coherence the Cholesky factor of the coherence matrix of equally spaced points
// is that of a first-order autoregression along the line, so the Fourier coefficient of point j
// at frequency f_k is c_j = rho c_{j-1} + sqrt(1 - rho^2) A_k e^{i phi_jk}, rho = exp(-C f_k dx / U),
// with phases phi uniform from a seeded mt19937_64, drawn point by point; each point's time
// series follows by an inverse FFT (Eigen's). The field is periodic in time with the period
// N dt_w (covering the pass, at most about 10 minutes); points between the grid's are linear in x
// and t.
// Time grid: the series are sampled at dt_w = 1 / (4 max_frequency), twice the Nyquist rate of
// the band, and the amplitudes are A_k = sqrt(2 S_u(f_k) df) / sinc^2(f_k dt_w): linear
// interpolation in time has the transfer function sinc^2(f dt_w) (a triangle's), which the
// amplitudes undo, so that the field the wires feel has S_u up to max_frequency. At twice the
// Nyquist rate the interpolation's images lie at 1/dt_w - f >= 3 max_frequency, where sinc^4 is
// below 1 %, and the boost at max_frequency is 1/sinc^4(1/4) = 1.52 in power (at the Nyquist rate
// it would be 6.1, with images as strong as the band's top next to it).
// Memory: a finite line holds every point's series, built with the model (LateralModel); an
// endless line holds the points of its block only, in a ring (WindFieldBuffer in its state), and
// generates the points ahead as the block moves on: a bounded buffer whatever the distance run.
// The same draw order makes both the same realisation where they reach the same stations.
#pragma once

#include <unsupported/Eigen/FFT>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "catenary_sim/core/scene/scene.hpp"

namespace catenary_sim {

// One-sided von Karman spectrum S_u(f) (m^2/s^2 per Hz).
double von_karman_spectrum(double f, double mean_speed, double sigma_u, double length_scale);

// The field's grid and spectrum (immutable, in the model). Its values: WindFieldBuffer.
struct WindField {
  double x0 = 0.0, dx = 1.0;  // m, first point and spacing
  int points = 0;             // along the stations the line covers (x0 + j dx, j < points)
  int held = 0;               // points a buffer holds at once (all of them on a finite line)
  double dt = 0.1;            // s, time step of the series
  int samples = 0;            // per point; the series repeats after samples x dt
  // Per frequency k df (k = 1 .. frequencies - 1, df = 1 / (samples dt)): the amplitude (with
  // the interpolation's compensation), the coherence from one point to the next, sqrt(1 - rho^2).
  int frequencies = 0;
  std::vector<double> amplitude, rho, innovation;
  std::uint64_t seed = 0;
  double sigma_target = 0.0;  // m/s, sqrt of the spectrum's integral over the generated band
  bool empty() const { return points == 0; }
  // Station x between points j and j + 1 with the linear weight a of j + 1 (clamped to the field).
  void locate(double x, int* j, double* a) const {
    const double q = (x - x0) / dx;
    *j = std::clamp(static_cast<int>(std::floor(q)), 0, points - 2);
    *a = std::clamp(q - *j, 0.0, 1.0);
  }
  // Bytes of one buffer's series and workspace (WindFieldBuffer::bytes).
  std::size_t buffer_bytes() const;
};

// The values of the field: the series of the points [first, end), at most `held` of them, in a
// ring; generated in order along the line and never regenerated.
class WindFieldBuffer {
 public:
  // Sizes everything once and generates the first held points.
  void reset(const WindField& f);
  // Generates the points up to `last` (clamped to the field), dropping the oldest to keep `held`:
  // no allocation (the FFT's plan and every buffer are made by reset).
  void extend_to(const WindField& f, int last);
  // The held points' values at time t: out[j - first()] for j in [first(), end()).
  void at_time(const WindField& f, double t, double* out) const;
  int first() const { return first_; }
  int end() const { return end_; }
  // Point j's sample n (j held).
  float sample(const WindField& f, int n, int j) const {
    return u_[static_cast<std::size_t>(n) * f.held + static_cast<std::size_t>(j % f.held)];
  }
  // The field at station x from at_time's values (clamped to the held points).
  double at(const WindField& f, const double* values, double x) const {
    int j = 0;
    double a = 0.0;
    f.locate(x, &j, &a);
    j = std::clamp(j, first_, std::max(first_, end_ - 2));
    return (1.0 - a) * values[j - first_] + a * values[j + 1 - first_];
  }
  std::size_t bytes() const;  // capacity of its buffers

 private:
  void generate(const WindField& f);  // the next point, end_
  std::vector<float> u_;  // u'[n * held + j % held] at time n dt and point j
  std::vector<std::complex<double>> c_, X_;  // the last point's coefficients; the FFT's input
  std::vector<double> series_;
  std::mt19937_64 gen_;
  // The FFT with its plan for `samples` points. Assigning a buffer of the same size keeps the
  // target's own plan (the same plan): restoring a snapshot of a state allocates nothing.
  struct Fft {
    Eigen::FFT<double> fft;
    int samples = 0;
    Fft() = default;
    Fft(const Fft&) = default;
    Fft& operator=(const Fft& other) {
      if (other.samples != samples) {
        fft = other.fft;
        samples = other.samples;
      }
      return *this;
    }
  };
  Fft fft_;
  int first_ = 0, end_ = 0;
};

// The field over [x_begin, x_end] for at least `duration` s (at least 60 s, at most about 600 s),
// holding at most enough points for `held_length` m at once (infinite: every point).
WindField make_wind_field(const WindSpec& wind, double x_begin, double x_end, double duration,
                          double held_length = std::numeric_limits<double>::infinity());

// Bytes a buffer of the field over `held_length` m takes (at most), from the scene's wind alone:
// for the model's memory estimate.
double wind_field_bytes_estimate(const WindSpec& wind, double held_length);

}  // namespace catenary_sim
