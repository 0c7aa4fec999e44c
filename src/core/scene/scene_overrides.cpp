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
  check_text(assignment, "an override (--set)");  // (before its bytes go into any message)
  const auto eq = assignment.find('=');
  auto bad = [&](const std::string& why) -> SceneError {
    // A long value (a list of hundreds of stations) is shown by its start and its length.
    std::size_t shown = 200;
    if (assignment.size() <= shown) return SceneError("override '" + assignment + "': " + why);
    while (shown > 0 && (static_cast<unsigned char>(assignment[shown]) & 0xC0) == 0x80) --shown;  // whole characters
    return SceneError("override '" + assignment.substr(0, shown) + "...' (" + std::to_string(assignment.size()) +
                      " characters): " + why);
  };
  if (eq == std::string::npos || eq == 0) throw bad("expected key.path=value, e.g. numerics.element_length=0.125");
  // A list entry as the error messages name it, name[i], is name.i: a field named in an error can
  // be set as it is written there.
  const std::string written = assignment.substr(0, eq);
  std::string key;
  for (std::size_t i = 0; i < written.size(); ++i) {
    if (written[i] != '[') {
      key += written[i];
      continue;
    }
    const std::size_t close = written.find(']', i);
    const std::string digits = close == std::string::npos ? "" : written.substr(i + 1, close - i - 1);
    const char after = close == std::string::npos || close + 1 >= written.size() ? '.' : written[close + 1];
    if (i == 0 || written[i - 1] == '.' || digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos ||
        (after != '.' && after != '['))
      throw bad("a list index in brackets is digits after a field's name, as in sections[1].span_count "
                "(or sections.1.span_count)");
    key += "." + digits;
    i = close;
  }
  YAML::Node value;
  try {
    value = YAML::Load(assignment.substr(eq + 1));
  } catch (const YAML::Exception& e) {
    throw bad("value is not valid YAML (" + yaml_error_text(e) + ")");
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
