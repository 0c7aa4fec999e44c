// Static problems: the design shape (dropper lengths that give the prescribed presag under the
// wires' own weight and the clamp masses) and the initial state with the pantographs pressed on
// (eq. 23, q_dot0 = 0 by eq. 24).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

// Statics of one wire with some nodes held at prescribed heights: returns (w, theta) per node in
// `height`/`slope` and the support reactions (N, upward positive) at the prescribed nodes.
// `node_load` is the vertical load on each node (N, upward positive). `solver` (model/spd_solver.hpp,
// private) keeps the ordering between solves of one wire; null: a solver of the call's own.
class SpdSolver;
void solve_wire_statics(const Wire& wire, const std::vector<double>& node_load,
                        const std::vector<int>& prescribed_nodes, const std::vector<double>& prescribed_heights,
                        std::vector<double>& height, std::vector<double>& slope, std::vector<double>& reactions,
                        SpdSolver* solver = nullptr);

// What the pantographs press with in the static problem: the train front's position (m) and,
// per pantograph, the static uplift in effect (N), an external pantograph's given force (N) and
// the square of its speed through the air (m^2/s^2, the v^2 of every aerodynamic uplift a v^2).
struct PantographLoads {
  double front = 0.0;
  std::vector<double> uplift, external_force, air_speed_squared;
};

// The loads at the model's start: each pantograph's static uplift (an external one's force too),
// the train at train_start at the scene's speed in still air.
PantographLoads design_pantograph_loads(const Model& model);

// Eq. 23: static equilibrium with every pantograph pressed on under `loads`, droppers
// tension-only and contacts compression-only (iterated to a consistent active set, eq. 25).
// Returns the displacements from the design state (Model::n_dof entries). Without
// `roof_springs` the roof springs are left out (relaxed at the working height). Throws
// SceneError if no consistent set is found. (engine/initial_state.hpp: a pass's initial state.)
Eigen::VectorXd solve_static_equilibrium(const Model& model, const PantographLoads& loads, bool roof_springs = true);

// Sets each pantograph's reference height and spring preloads so that, at the initial static
// state, the static uplift is exactly the static contact force (part of building the model).
void set_pantograph_references(Model& model);

// Heights d (m) by which each section's contact wire support is raised at its first and last
// support (0 where the end span is a current span): overlap.support_rise, or eq. 6-8 with
// h = E F, E measured on the model at the middle of a current span of the section.
std::vector<double> transition_support_rises(const Scene& scene);

// Static elasticity of the line: a stiff probe collector pressed up with `force` at a station
// (eq. 23, droppers tension-only). Used for eq. 6 (h = E F) and for elasticity curves.
class ElasticityProbe {
 public:
  ElasticityProbe(const Scene& scene, double force, const std::optional<std::vector<double>>& support_rises = std::nullopt);
  // Static uplift (m) of every contact wire (Model::contact_wires order) under the probe at
  // station x; NaN for a wire the probe does not touch there.
  std::vector<double> uplift(double x) const;
  const Model& model() const { return model_; }

 private:
  Model model_;
};

}  // namespace catenary_sim
