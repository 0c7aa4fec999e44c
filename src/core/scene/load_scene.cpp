// Loading a scene: the file (size-capped), the YAML text, the overrides, then the reader.
#include <sys/stat.h>
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "catenary_sim/core/scene/scene.hpp"
#include "scene/capped_file.hpp"
#include "scene/document_shape.hpp"
#include "scene/scene_overrides.hpp"

namespace catenary_sim {

namespace {

Scene load_from_node(YAML::Node root, const std::vector<std::string>& overrides, const std::string& base_dir) {
  if (!root || !root.IsMap()) throw SceneError("scene: the document must be a YAML map of sections (line, contact_wire, ...)");
  try {
    for (const auto& o : overrides) apply_override(root, o);
    check_document(root, "");
    return scene_from_yaml(root, base_dir);
  } catch (const YAML::Exception& e) {
    // Not expected after check_document; a field is still better named by the reader, but never abort.
    throw SceneError(std::string("scene: ") + e.what());
  } catch (const std::logic_error& e) {
    throw SceneError(std::string("scene: ") + e.what());
  }
}

}  // namespace

Scene load_scene_string(const std::string& yaml, const std::vector<std::string>& overrides, const std::string& base_dir) {
  check_text(yaml, "scene");
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw SceneError("scene: not valid YAML: " + yaml_error_text(e));
  }
  check_yaml_shape(yaml, "scene");
  return load_from_node(root, overrides, base_dir);
}


Scene load_scene_file(const std::string& path, const std::vector<std::string>& overrides) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw SceneError("scene file '" + path + "': cannot be opened (" + std::strerror(errno) + ")");
  if (S_ISDIR(st.st_mode)) throw SceneError("scene file '" + path + "': is a directory, expected a YAML file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError("scene file '" + path + "': cannot be opened (" + std::strerror(errno) + ")");
  const std::string text = read_capped(in, kMaxSceneFileBytes);
  if (text.size() > kMaxSceneFileBytes)
    throw SceneError("scene file '" + path + "': larger than " + std::to_string(kMaxSceneFileBytes >> 20) +
                     " MiB, the limit for a scene (scenes are a few kB of YAML)");
  if (in.bad()) throw SceneError("scene file '" + path + "': read error (" + std::strerror(errno) + ")");
  try {
    const std::size_t slash = path.rfind('/');
    Scene scene = load_scene_string(text, overrides, slash == std::string::npos ? "" : path.substr(0, slash == 0 ? 1 : slash));
    scene.file = path;
    return scene;
  } catch (const SceneError& e) {
    throw SceneError(path + ": " + e.what());
  }
}

}  // namespace catenary_sim
