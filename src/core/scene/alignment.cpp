// The track in plan: straight, circular curves and clothoid transitions (curvature linear in the
// station), as curvature and heading along the line.
#include <cmath>

#include "catenary_sim/core/scene/scene.hpp"

namespace catenary_sim {

double AlignmentSpec::curvature(double x) const {
  if (radius != 0.0) return 1.0 / radius;
  for (const CurveSpec& c : curves) {
    const double s = x - c.start;
    if (s < 0.0 || s > c.length) continue;
    const double k = 1.0 / c.radius;
    if (c.transition > 0.0) {
      if (s < c.transition) return k * s / c.transition;
      if (s > c.length - c.transition) return k * (c.length - s) / c.transition;
    }
    return k;
  }
  return 0.0;
}

double AlignmentSpec::heading(double x) const {
  // Integral of the curvature from 0 to x (trapezoids are exact on the linear pieces); an
  // endless line on one radius keeps its heading (AlignmentSpec::radius).
  if (radius != 0.0) return 0.0;
  double psi = 0.0;
  for (const CurveSpec& c : curves) {
    if (x <= c.start) break;
    const double k = 1.0 / c.radius, s = std::min(x - c.start, c.length), tr = c.transition;
    if (tr <= 0.0) {
      psi += k * s;
      continue;
    }
    const double a = std::min(s, tr);
    psi += 0.5 * k * a * a / tr;  // entry transition
    if (s > tr) psi += k * (std::min(s, c.length - tr) - tr);
    if (s > c.length - tr) {
      const double b = s - (c.length - tr);  // into the exit transition
      psi += k * b - 0.5 * k * b * b / tr;
    }
  }
  return psi;
}

}  // namespace catenary_sim
