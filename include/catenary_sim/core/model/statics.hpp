// Static problems: the design shape (dropper lengths that give the prescribed presag under the
// wires' own weight and the clamp masses) and the initial state with the pantographs pressed on
// (eq. 23, q_dot0 = 0 by eq. 24).
#pragma once

#include <vector>

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/engine/state.hpp"

namespace catenary_sim {

// Statics of one wire with some nodes held at prescribed heights: returns (w, theta) per node in
// `height`/`slope` and the support reactions (N, upward positive) at the prescribed nodes.
// `node_load` is the vertical load on each node (N, upward positive).
void solve_wire_statics(const Wire& wire, const std::vector<double>& node_load,
                        const std::vector<int>& prescribed_nodes, const std::vector<double>& prescribed_heights,
                        std::vector<double>& height, std::vector<double>& slope, std::vector<double>& reactions);

// Eq. 23: static equilibrium with every pantograph pressed on at the train position of `state`,
// droppers tension-only and contacts compression-only (iterated to a consistent active set).
// Writes state.u and zeroes state.v (eq. 24). Throws SceneError if no consistent set is found.
void solve_initial_state(const Model& model, State& state, bool roof_springs = true);

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
