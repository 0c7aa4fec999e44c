#include "catenary_sim/hil/rig_pantograph.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace catenary_sim {
namespace hil {

RigPantograph::RigPantograph(const PantographSpec& spec, double k0) : spec_(spec), k0_(k0) {
  if (spec.moving_force || spec.external || spec.masses.empty())
    throw std::invalid_argument("virtual rig: pantograph '" + spec.name +
                                "' is not a lumped pantograph with masses (type lumped)");
  // The rig's pantograph is a chain (eq. 9) pressing one contact point; a head on its own
  // suspension would need the tree and per-head contacts: refused rather than silently merged.
  if (!spec.heads.empty())
    throw std::invalid_argument("virtual rig: pantograph '" + spec.name + "' has " + std::to_string(spec.heads.size()) +
                                " heads on their own suspensions (pantographs[].heads); allowed: a chain without "
                                "heads (masses, stiffness, damping, head first)");
  if (spec.stiffness.size() != spec.masses.size() || spec.damping.size() != spec.masses.size())
    throw std::invalid_argument("virtual rig: pantograph '" + spec.name + "': one stiffness and damping per mass");
  for (double m : spec.masses)
    if (!(m > 0.0)) throw std::invalid_argument("virtual rig: pantograph '" + spec.name + "': masses must be > 0");
  if (!(k0 > 0.0) || !std::isfinite(k0)) throw std::invalid_argument("virtual rig: contact stiffness must be > 0");
  d_.assign(spec.masses.size(), 0.0);
  v_.assign(spec.masses.size(), 0.0);
  f_.assign(spec.masses.size(), 0.0);
}

void RigPantograph::reset(const std::vector<WirePoint>& points, double speed) {
  static_force_ = spec_.static_uplift + spec_.aero_coefficient * speed * speed;
  std::vector<double> y;
  for (const WirePoint& p : points)
    if (p.on_wire) y.push_back(p.height);
  std::sort(y.begin(), y.end());
  // Head height h with sum over the points of max(0, k0 (h - y_i)) = static force: pressed on the
  // lowest m points, h = (F/k0 + sum y_i) / m, for the first m at which h does not reach y_(m+1).
  head_static_ = y.empty() ? 0.0 : y[0];
  double sum = 0.0;
  for (std::size_t m = 1; m <= y.size(); ++m) {
    sum += y[m - 1];
    const double h = (static_force_ / k0_ + sum) / static_cast<double>(m);
    head_static_ = h;
    if (m == y.size() || h <= y[m]) break;
  }
  std::fill(d_.begin(), d_.end(), 0.0);
  std::fill(v_.begin(), v_.end(), 0.0);
}

double RigPantograph::contact_force(const std::vector<WirePoint>& points, double ahead) const {
  const double head = head_height();
  double f = 0.0;
  for (const WirePoint& p : points)
    if (p.on_wire) f += std::max(0.0, k0_ * (head - (p.height + ahead * p.path_velocity)));
  return f;
}

void RigPantograph::step(double dt, double contact, double speed) {
  const std::size_t n = d_.size();
  std::fill(f_.begin(), f_.end(), 0.0);
  // The spring (and damper) below mass i joins it to mass i + 1, the last to the roof. Between
  // masses the springs carry the static force at displacement 0; the roof spring is relaxed there.
  for (std::size_t i = 0; i < n; ++i) {
    const bool roof = i + 1 == n;
    const double db = roof ? 0.0 : d_[i + 1], vb = roof ? 0.0 : v_[i + 1];
    const double preload = roof ? 0.0 : static_force_;
    const double c = preload + spec_.stiffness[i] * (db - d_[i]) + spec_.damping[i] * (vb - v_[i]);
    f_[i] += c;
    if (!roof) f_[i + 1] -= c;
  }
  f_[n - 1] += spec_.static_uplift + spec_.aero_coefficient * speed * speed;
  f_[0] -= contact;
  for (std::size_t i = 0; i < n; ++i) {
    v_[i] += dt * ((1.0 / spec_.masses[i]) * f_[i]);  // as the core: inv_mass x force
    d_[i] += dt * v_[i];
  }
}

void RigStepper::restart(std::vector<RigPantograph> rigs, std::vector<std::vector<WirePoint>> points,
                         std::uint32_t pass, std::uint64_t step, double dt, double speed) {
  rigs_ = std::move(rigs);
  points_ = std::move(points);
  for (std::size_t i = 0; i < rigs_.size() && i < points_.size(); ++i) rigs_[i].reset(points_[i], speed);
  have_ = true;
  pass_ = pass;
  step_ = step;
  dt_ = dt;
  speed_ = speed;
}

void RigStepper::advance(std::uint64_t step, std::vector<std::vector<WirePoint>>& points, double dt, double speed) {
  // Step up to the new state, against the wire of the previous contact point.
  for (std::size_t i = 0; i < rigs_.size(); ++i) {
    for (std::uint64_t s = step_; s < step; ++s) {
      const double ahead = extrapolate_ ? static_cast<double>(s - step_) * dt_ : 0.0;
      rigs_[i].step(dt_, rigs_[i].contact_force(points_[i], ahead), speed_);
    }
  }
  points_.swap(points);
  step_ = step;
  dt_ = dt;
  speed_ = speed;
}

}  // namespace hil
}  // namespace catenary_sim
