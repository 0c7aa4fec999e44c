// The YAML document's shape, checked before any field is read: one acyclic document of bounded
// alias expansion (check_yaml_shape, on the text), every key a plain name given once and no empty
// value (check_document, on the tree).
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

namespace catenary_sim {

// Throws SceneError for a key that is not a plain name, a key given twice or an empty value.
void check_document(const YAML::Node& n, const std::string& path);

// Throws SceneError (naming `what`) for YAML that is not one acyclic document of bounded expansion.
void check_yaml_shape(const std::string& text, const std::string& what);

}  // namespace catenary_sim
