// The scene's imperfections room: the line as built (dropper lengths, support heights, stagger
// errors, point masses, contact wire irregularity and wear), profiles from CSV files.
#pragma once

#include <string>

#include "scene/scene_reader.hpp"

namespace catenary_sim {

// base_dir: where a profile's relative csv file name is looked up.
void read_imperfections(scene_reading::Reader& top, Scene& s, const std::string& base_dir);

}  // namespace catenary_sim
