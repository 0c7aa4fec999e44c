// Overrides of the scene's fields given on a command line ("--set key.path=value").
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

namespace catenary_sim {

// Applies "a.b.0.c=value" (or "a.b[0].c=value", as error messages name list entries) to the
// tree. A value of null removes the field (back to its default).
// Throws SceneError naming the assignment.
void apply_override(YAML::Node root, const std::string& assignment);

}  // namespace catenary_sim
