#include "scene/scene_overrides.hpp"

#include <limits>
#include <sstream>
#include <vector>

#include "catenary_sim/core/scene/scene.hpp"
#include "scene/document_shape.hpp"

namespace catenary_sim {

namespace {

// A part of a dotted key that indexes a list: digits only, small enough to be an index.
bool index_of(const std::string& part, std::size_t* idx) {
  if (part.empty() || part.find_first_not_of("0123456789") != std::string::npos) return false;
  *idx = part.size() > 9 ? std::numeric_limits<std::size_t>::max() : std::stoul(part);
  return true;
}

}  // namespace

void apply_override(YAML::Node root, const std::string& assignment) {
  const auto eq = assignment.find('=');
  auto bad = [&](const std::string& why) -> SceneError {
    return SceneError("override '" + assignment + "': " + why);
  };
  if (eq == std::string::npos || eq == 0) throw bad("expected key.path=value, e.g. numerics.element_length=0.125");
  const std::string key = assignment.substr(0, eq);
  YAML::Node value;
  try {
    value = YAML::Load(assignment.substr(eq + 1));
  } catch (const YAML::Exception& e) {
    throw bad(std::string("value is not valid YAML (") + e.what() + ")");
  }
  check_yaml_shape(assignment.substr(eq + 1), "override '" + assignment + "'");
  std::vector<std::string> parts;
  std::stringstream ss(key);
  for (std::string p; std::getline(ss, p, '.');) parts.push_back(p);
  if (key.back() == '.') parts.push_back("");
  for (const std::string& p : parts)
    if (p.empty()) throw bad("empty part in the key '" + key + "' (fields are joined by single dots)");
  // Walk down, creating maps as needed; numeric parts index lists.
  YAML::Node cur = root;
  std::string walked;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const std::string& part = parts[i];
    const bool leaf = i + 1 == parts.size();
    const std::string here = walked.empty() ? "the scene" : "'" + walked + "'";
    std::size_t idx = 0;
    if (cur.IsSequence()) {
      if (!index_of(part, &idx)) throw bad(here + " is a list: expected " + (cur.size() ? "an index 0.." + std::to_string(cur.size() - 1) : std::string("no index (it is empty)")) + ", not '" + part + "'");
      if (idx >= cur.size())
        throw bad("index " + part + " out of range: " + here + " has " + std::to_string(cur.size()) + " entries");
      if (leaf) {
        if (value.IsNull()) throw bad("a list entry cannot be removed with null");
        cur[idx] = value;
        return;
      }
      cur.reset(cur[idx]);
    } else if (cur.IsMap() || cur.IsNull() || !cur.IsDefined()) {
      if (leaf) {
        if (value.IsNull()) {
          if (cur.IsMap()) cur.remove(part);
        } else {
          cur[part] = value;
        }
        return;
      }
      if (!cur[part] || cur[part].IsNull()) cur[part] = YAML::Node(YAML::NodeType::Map);
      cur.reset(cur[part]);
    } else {
      throw bad(here + " is a value ('" + cur.Scalar() + "'), it has no field '" + part + "'");
    }
    walked += (walked.empty() ? "" : ".") + part;
  }
}

}  // namespace catenary_sim
