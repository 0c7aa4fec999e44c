// Sparse assembly helpers shared by the static solves and the implicit integrator (internal).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

using Triplets = std::vector<Eigen::Triplet<double>>;

// The wire's stiffness band, w of node i at w0 + i and theta at t0 + i.
void add_wire_band(Triplets& t, const Wire& w, int w0, int t0);

// A spring between DOF a (above) and b (below, -1 = ground) with compression C = P + k (x_b - x_a);
// the preload goes to the right-hand side r.
void add_spring(Triplets& t, Eigen::VectorXd& r, int a, int b, double k, double preload);

}  // namespace catenary_sim
