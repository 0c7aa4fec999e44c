// The wires packed for the fused explicit step, seen from outside the core: how many packs a model
// has and how many wires each runs side by side (their layout is private: Model::wire_packs).
#pragma once

#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

// Packs of the fused step; 0: the model takes the generic step (implicit, or rotations as DOFs).
int wire_pack_count(const Model& model);
// Wires (lanes) in pack `pack`, 0 <= pack < wire_pack_count: 2 for a contact wire and a messenger
// on the same node stations, else 1.
int wire_pack_lanes(const Model& model, int pack);

}  // namespace catenary_sim
