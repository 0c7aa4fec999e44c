// The wires packed for the fused explicit step (Model::wire_packs).
#pragma once

#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

// Packs the wires for the fused step (Model::wire_packs) when the model is explicit with condensed
// rotations; leaves them empty otherwise.
void build_wire_packs(Model& model);

}  // namespace catenary_sim
