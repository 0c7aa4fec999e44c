// The moving window's lengths (numerics.window; window_lengths.cpp).
#pragma once

#include "catenary_sim/core/scene/scene.hpp"

namespace catenary_sim {

struct Model;

// Lengths (m) the moving window integrates ahead of the foremost and behind the rearmost
// pantograph at a train speed (m/s): the scene's, or for `window: auto` the distances the
// contact wire's waves run from the pantograph in the time they take to fade .
void window_lengths(const Model& model, double speed_mps, double* ahead, double* behind);

// The window's lengths (m) ahead and behind at a train speed (m/s), for a contact wire of wave
// speed c (m/s) and spans of `span` m: the scene's, or the auto rule.
void window_lengths_for(const NumericsSpec& numerics, double wave_speed, double span, double speed, double* ahead,
                        double* behind);

}  // namespace catenary_sim
