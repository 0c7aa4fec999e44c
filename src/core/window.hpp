// Moving window internals (see window.cpp).
#pragma once

#include "catenary_sim/core/model.hpp"
#include "catenary_sim/core/state.hpp"

namespace catenary_sim {

// Moves the window to the pantographs if they crossed into another span; no allocation.
void update_window(const Model& model, State& state);

// -K z over the window's nodes of one wire (condensed rotations, cut ends left free).
void wire_elastic_force_window(const Wire& wire, const WireWindow& window, const double* z, double* f, double* theta);

}  // namespace catenary_sim
