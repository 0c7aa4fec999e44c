// A pass's initial state: the line's statics with the pantographs pressed on (eq. 23), at rest
// (q_dot0 = 0, eq. 24), for the train position and forces a State holds.
#pragma once

#include "catenary_sim/core/engine/state.hpp"
#include "catenary_sim/core/model/statics.hpp"

namespace catenary_sim {

// What the state's pantographs press with: its train front, the uplifts and external forces in
// effect, and each pantograph's speed through the air (train speed plus head wind).
PantographLoads pantograph_loads(const Model& model, const State& state);

// Eq. 23: static equilibrium with every pantograph pressed on at the train position of `state`,
// droppers tension-only and contacts compression-only (iterated to a consistent active set).
// Writes state.u and zeroes state.v (eq. 24). Throws SceneError if no consistent set is found.
void solve_initial_state(const Model& model, State& state, bool roof_springs = true);

}  // namespace catenary_sim
