// The implicit step (implicit_step.cpp): Newmark's average acceleration on the matrix factorised
// once (Model::implicit), what switches entering as rank-1 corrections.
#pragma once

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/engine/state.hpp"

namespace catenary_sim {

// One Newmark step (the state neither stopped nor at the pass's end).
StepStatus implicit_step(const Model& m, State& s);

}  // namespace catenary_sim
