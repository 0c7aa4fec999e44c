// Stability of the explicit central differences (validation.md section 5): the highest
// eigenfrequency of the assembled system and the critical time step it allows.
#pragma once

#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

// Highest eigenfrequency (rad/s) of M^-1 K with every dropper and contact active, by power
// iteration on the symmetrised operator M^-1/2 K M^-1/2 (DOFs held rigidly are left out). With
// `explicit_part`, of the K the explicit step takes at q_n (apply_stiffness).
double highest_eigenfrequency(const Model& model, int iterations = 3000, bool explicit_part = false);

// dt_crit = (2 / w_max) (sqrt(1 + xi^2) - xi), xi = alpha / (2 w_max) + beta w_max / 2.
double critical_time_step(double omega_max, double alpha, double beta);

// Sets model.omega_max (the estimate with a 0.2 % safety margin, plus a bound for the contacts
// wherever they are along the line) and model.dt_critical.
void compute_stability_limit(Model& model);

}  // namespace catenary_sim
