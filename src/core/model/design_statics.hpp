// The line's design statics: the heights of the wires and the lengths and tensions of the droppers
// that hold the contact wire at its design shape, and the support preloads.
#pragma once

#include <vector>

#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

// section_supports: per section, the station of each of its supports.
void design_statics(const Scene& scene, const std::vector<std::vector<double>>& section_supports, Model& m);

}  // namespace catenary_sim
