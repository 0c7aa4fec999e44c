// The explicit step (explicit_step.cpp): central differences with the half-step velocity, paper
// eq. 19-21, 26.
#pragma once

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/engine/state.hpp"

namespace catenary_sim {

// One step of eq. 19-21 (the state neither stopped nor at the pass's end): the endless block and
// the window moved first, then the fused sweeps (Model::wire_packs) where they can take the
// state, else the generic step; both give the same bits.
StepStatus explicit_step(const Model& m, State& s);

}  // namespace catenary_sim
