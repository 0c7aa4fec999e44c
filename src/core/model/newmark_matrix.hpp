// The implicit integrator's constant part: Newmark average acceleration (beta 1/4, gamma 1/2) on
// M + dt/2 C + dt^2/4 K0 (every dropper taut, no contact), factorised once (sparse LDL^T with a fill-reducing ordering) and solved
// every step by hand in preallocated storage.
#pragma once

#include <memory>
#include <vector>

#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

// The Newmark matrix M + dt/2 C + dt^2/4 K0, factorised once: L D L^T of P A P^T with L unit
// lower triangular (strict part in compressed columns).
struct ImplicitMatrix {
  std::vector<int> perm;           // P as indices: (P b)[perm[i]] = b[i]
  std::vector<int> col, row;       // CSC of the strict lower part of L
  std::vector<double> val;
  std::vector<double> inv_diag;    // 1 / D
};

std::shared_ptr<const ImplicitMatrix> newmark_matrix(const Model& model, double dt);

// Solves A x = b in place (b becomes x); tmp has n entries. No allocation.
void newmark_solve(const ImplicitMatrix& a, double* b, double* tmp);

}  // namespace catenary_sim
