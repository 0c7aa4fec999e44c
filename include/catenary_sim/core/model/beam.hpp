// Pre-stressed Euler-Bernoulli beam element (paper eq. 3: (p/g) y'' + EI y'''' - T y'' + p = 0)
// with cubic Hermite shape functions, DOF order (w1, theta1, w2, theta2).
#pragma once

#include <array>

namespace catenary_sim {

using Matrix4 = std::array<std::array<double, 4>, 4>;

// Bending stiffness EI/h^3 [12 6h -12 6h; ...] plus the geometric (tension) stiffness
// T/(30h) [36 3h -36 3h; ...] of a wire element of length h.
inline Matrix4 beam_stiffness(double h, double EI, double T) {
  const double b = EI / (h * h * h), g = T / (30.0 * h);
  const double h2 = h * h;
  Matrix4 k{};
  const double kb[4][4] = {{12, 6 * h, -12, 6 * h}, {6 * h, 4 * h2, -6 * h, 2 * h2},
                           {-12, -6 * h, 12, -6 * h}, {6 * h, 2 * h2, -6 * h, 4 * h2}};
  const double kg[4][4] = {{36, 3 * h, -36, 3 * h}, {3 * h, 4 * h2, -3 * h, -h2},
                           {-36, -3 * h, 36, -3 * h}, {3 * h, -h2, -3 * h, 4 * h2}};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) k[i][j] = b * kb[i][j] + g * kg[i][j];
  return k;
}

// HRZ lumping of the consistent mass: rhoA h / 2 on each w, rhoA h^3 / 78 on each theta.
inline double beam_translational_mass(double h, double rhoA) { return 0.5 * rhoA * h; }
inline double beam_rotary_mass(double h, double rhoA) { return rhoA * h * h * h / 78.0; }

}  // namespace catenary_sim
