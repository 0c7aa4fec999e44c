// The implicit integrator's constant part: Newmark average acceleration (beta 1/4, gamma 1/2) on
// M + dt/2 C + dt^2/4 K0, factorised once (sparse LDL^T with a fill-reducing ordering) and solved
// every step by hand in preallocated storage.
#pragma once

#include <memory>

#include "catenary_sim/core/model.hpp"

namespace catenary_sim {

// Highest frequency (rad/s) of the parts the implicit scheme evaluates explicitly at the
// prediction (the tension-only droppers): dt must stay below 2 / this.
double explicit_parts_frequency(const Model& model);

std::shared_ptr<const ImplicitMatrix> newmark_matrix(const Model& model, double dt);

// Solves A x = b in place (b becomes x); tmp has n entries. No allocation.
void newmark_solve(const ImplicitMatrix& a, double* b, double* tmp);

}  // namespace catenary_sim
