// An endless line (Scene::endless): the block of equal spans the model holds, moved back a span at
// a time by the step.
#pragma once

#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

// Offsets from the train front (m) of the foremost and rearmost collectors of all pantographs
// (collector station - front); both 0 without collectors.
void collector_extent(const Scene& scene, double* lead, double* rear);

// Lays out the block: the scene's spans (and dropper positions) for the block, Model's endless_*
// fields and the initial line offset, the train start in block stations. Returns the train front
// at the start as a station along the endless line.
double lay_endless_block(Scene& scene, Model& m);

// Throws SceneError unless the block's spans where the window goes are identical; sets
// Model::span_nodes.
void check_endless_block(Model& m);

}  // namespace catenary_sim
