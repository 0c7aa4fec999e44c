// The scene's pantographs room: the lumped-mass chain, heads on their own suspension, collectors.
#pragma once

#include "scene/scene_reader.hpp"

namespace catenary_sim {

// pantographs: a list, each read into Scene::pantographs.
void read_pantographs(scene_reading::Reader& top, Scene& s);

}  // namespace catenary_sim
