// Wind on the wires (the loads' room, not the integrator's): the mean speed, and a seeded
// along-wind turbulent field u'(x, t) along the line generated once when the model is built.
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
// A_k = sqrt(2 S_u(f_k) df), with phases phi uniform from a seeded mt19937_64; the time series
// follow by an inverse FFT (Eigen's). The field is periodic in time with the period N dt_w, chosen
// to cover the pass; points between the grid's are linear in x and t.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "catenary_sim/core/scene.hpp"

namespace catenary_sim {

// One-sided von Karman spectrum S_u(f) (m^2/s^2 per Hz).
double von_karman_spectrum(double f, double mean_speed, double sigma_u, double length_scale);

struct WindField {
  double x0 = 0.0, dx = 1.0;  // m, first point and spacing
  int points = 0;
  double dt = 0.1;            // s, time step of the series
  int samples = 0;            // per point; the series repeats after samples x dt
  std::vector<float> u;       // m/s, u'[n * points + j] at time n dt and point j
  double sigma_target = 0.0;  // m/s, sqrt of the spectrum's integral over the generated band
  bool empty() const { return points == 0; }
  // Values at all points at time t (out: `points` entries).
  void at_time(double t, double* out) const;
  // Station x between points j and j + 1 with the linear weight a of j + 1 (clamped to the field).
  void locate(double x, int* j, double* a) const {
    const double q = (x - x0) / dx;
    *j = std::clamp(static_cast<int>(std::floor(q)), 0, points - 2);
    *a = std::clamp(q - *j, 0.0, 1.0);
  }
  // The field at station x from its values at all points at one time (at_time's out).
  double at(const double* values, double x) const {
    int j = 0;
    double a = 0.0;
    locate(x, &j, &a);
    return (1.0 - a) * values[j] + a * values[j + 1];
  }
};

// The field over [x_begin, x_end] for at least `duration` s (at least 60 s, at most 2^16 samples).
WindField make_wind_field(const WindSpec& wind, double x_begin, double x_end, double duration);

}  // namespace catenary_sim
