// The 3-D line's rooms of the scene: stagger, alignment, wind, pantograph_head (scene.hpp).
#pragma once

#include "scene/scene_reader.hpp"

namespace catenary_sim {

void read_lateral_parts(scene_reading::Reader& top, Scene& s);

}  // namespace catenary_sim
