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

// The parser's message for a YAML error; nesting deeper than the parser's limit is said so (the
// parser's own message for it is "bad file").
std::string yaml_error_text(const YAML::Exception& e);

// Throws SceneError (naming `what`, the line and the column) for text that is not UTF-8 or holds a
// NUL byte: a binary file, whose bytes the YAML parser would echo into its message (a message
// Python cannot decode) or read past. Text starting with a UTF-16 or UTF-32 byte-order mark is
// left to the parser, which reads those encodings.
void check_text(const std::string& text, const std::string& what);

}  // namespace catenary_sim
