// The line as built, not as designed (Scene::imperfections), applied to the built model.
#pragma once

#include <vector>

#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

// Dropper length and support height errors, the contact wire's irregularity and point masses.
void apply_imperfections(const Scene& scene, Model& m, const std::vector<bool>& fixed);

// A worn contact wire: lighter and less stiff in bending where worn (imperfections.contact_wire_wear).
void apply_wear(const Scene& scene, Model& m);

}  // namespace catenary_sim
