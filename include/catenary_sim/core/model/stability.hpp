// Stability of the explicit central differences (validation.md section 5): the highest
// eigenfrequency of the assembled system and the critical time step it allows.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

// Highest eigenfrequency (rad/s) of M^-1 K over n DOFs by power iteration on the symmetrised
// M^-1/2 K M^-1/2, `inv_sqrt_mass` its M^-1/2 (0 on rigidly held DOFs, left out), apply(x, y)
// writing y = K x. It starts from the saw-tooth (+1, -1, ...), the shape of a wire's highest mode,
// perturbed aperiodically so that no mode is missed; its Rayleigh quotient rises monotonically
// toward lambda_max, so it stops once that has settled (or after `iterations`), an estimate from
// below. Both planes' stability limits take it (highest_eigenfrequency; lateral.cpp).
template <class ApplyK>
double power_iteration_omega(int n, const double* inv_sqrt_mass, int iterations, ApplyK apply) {
  const double* s = inv_sqrt_mass;
  std::vector<double> x(n), y(n), tmp(n);
  for (int i = 0; i < n; ++i) x[i] = s[i] > 0.0 ? ((i % 2) ? 1.0 : -1.0) * (1.0 + 0.1 * std::sin(0.7 * i)) : 0.0;
  double lambda = 0.0, checkpoint = 0.0;
  for (int it = 0; it < iterations; ++it) {
    if (it % 50 == 49) {
      if (lambda - checkpoint <= 1e-10 * lambda) break;
      checkpoint = lambda;
    }
    double norm = 0.0;
    for (int i = 0; i < n; ++i) norm += x[i] * x[i];
    norm = std::sqrt(norm);
    if (!std::isfinite(norm)) {
      // The squares overflowed (lambda above about 1e154: a mass of next to nothing on a spring):
      // x scaled by its largest entry first. Never taken on a line the step can run, so that its
      // estimate keeps its bits.
      double largest = 0.0;
      for (int i = 0; i < n; ++i) largest = std::max(largest, std::fabs(x[i]));
      if (!std::isfinite(largest)) return std::numeric_limits<double>::infinity();
      norm = 0.0;
      for (int i = 0; i < n; ++i) {
        x[i] /= largest;
        norm += x[i] * x[i];
      }
      norm = std::sqrt(norm);
    }
    if (norm == 0.0) return 0.0;
    for (int i = 0; i < n; ++i) tmp[i] = s[i] * x[i] / norm;
    apply(tmp.data(), y.data());
    double rq = 0.0;
    for (int i = 0; i < n; ++i) {
      y[i] *= s[i];
      rq += y[i] * x[i] / norm;
    }
    lambda = rq;
    x.swap(y);
  }
  return std::isnan(lambda) ? std::numeric_limits<double>::infinity() : std::sqrt(std::max(lambda, 0.0));
}

// Highest eigenfrequency (rad/s) of M^-1 K with every dropper and contact active, by power
// iteration on the symmetrised operator M^-1/2 K M^-1/2 (DOFs held rigidly are left out). With
// `explicit_part`, of the K the explicit step takes at q_n (apply_stiffness).
double highest_eigenfrequency(const Model& model, int iterations = 3000, bool explicit_part = false);

// dt_crit = (2 / w_max) (sqrt(1 + xi^2) - xi), xi = alpha / (2 w_max) + beta w_max / 2.
double critical_time_step(double omega_max, double alpha, double beta);

// The limit explicit dampers on point springs and masses set where no band estimate holds them
// (the centred step's springs with their beta k, the pantographs' dampers): each DOF's springs
// and dampers bounded by its Gershgorin rows of M^-1/2 K M^-1/2 and M^-1/2 C M^-1/2 (a link
// between two masses adds k / m_i + k / sqrt(m_i m_j): its relative mode, sqrt(k (1/m_i + 1/m_j)),
// is above either mass's sqrt(k / m) alone), taken as one DOF: w^2 and the damping rate in the
// formula above (validation.md section 5).
class PointDampingLimit {
 public:
  explicit PointDampingLimit(const Eigen::VectorXd& inv_mass)
      : inv_mass_(inv_mass), k_row_(inv_mass.size(), 0.0), c_row_(inv_mass.size(), 0.0) {}
  // A spring k and damper c from DOF `dof` to the ground (a support, the roof, a wire taken held).
  void ground(int dof, double k, double c) {
    k_row_[dof] += k * inv_mass_[dof];
    c_row_[dof] += c * inv_mass_[dof];
  }
  // A spring k and damper c between DOFs a and b (a dropper, a clamp, a pantograph's frame).
  void link(int a, int b, double k, double c) {
    const double cross = std::sqrt(inv_mass_[a] * inv_mass_[b]);
    for (const int i : {a, b}) {
      k_row_[i] += k * (inv_mass_[i] + cross);
      c_row_[i] += c * (inv_mass_[i] + cross);
    }
  }
  // The least step over the DOFs with a damper (2 / rate for a damper without a spring); infinity
  // without one.
  double time_step() const {
    double dt = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < k_row_.size(); ++i) {
      if (!(c_row_[i] > 0.0)) continue;
      dt = std::min(dt, k_row_[i] > 0.0 ? critical_time_step(std::sqrt(k_row_[i]), c_row_[i], 0.0) : 2.0 / c_row_[i]);
    }
    return dt;
  }

 private:
  const Eigen::VectorXd& inv_mass_;
  std::vector<double> k_row_, c_row_;
};

// Sets model.omega_max (the wires' estimate with a 0.2 % safety margin, or `coupled_omega` when
// given: the planes' lean-coupled frequency, found above that estimate, plus a bound for the
// contacts wherever they are along the line) and model.dt_critical; returns the wires' part.
double compute_stability_limit(Model& model, double coupled_omega = 0.0);

}  // namespace catenary_sim
