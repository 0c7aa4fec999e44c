// The train's motion at the end of every step (train_motion.cpp).
#pragma once

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/engine/state.hpp"

namespace catenary_sim {

// Train kinematics: toward the commanded speed within the acceleration limit.
double next_speed(const State& s, double dt);

// The end of every step: the train moves, the clock advances, and the observations are taken on
// the new state (t_{n+1}), so a snapshot is always consistent.
void advance_train(const Model& m, State& s, double dt);

}  // namespace catenary_sim
