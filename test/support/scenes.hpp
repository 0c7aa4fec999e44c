// Scenes the tests build from the shipped configs. Header-only.
#pragma once

#include <sstream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "catenary_sim/core/scene/scene.hpp"

// The source tree: the build defines it for the tests.
#ifndef CATENARY_SIM_SOURCE_DIR
#define CATENARY_SIM_SOURCE_DIR "."
#endif

namespace test_scenes {

// The shipped scenes.
inline const std::string kConfigDir = CATENARY_SIM_SOURCE_DIR "/config/";

// The reference catenary as one 6-span section with a twin contact wire: three wires on the same
// stations, packed as two lanes and one.
inline catenary_sim::Scene twin_contact_wire(const std::vector<std::string>& overrides) {
  YAML::Node root = YAML::LoadFile(kConfigDir + "reference_55m.yaml");
  root["line"].remove("span_length");
  root["line"].remove("span_count");
  YAML::Node sec;
  sec["span_length"] = 55.0;
  sec["span_count"] = 6;
  sec["contact_wire_count"] = 2;
  root["sections"].push_back(sec);
  std::stringstream s;
  s << root;
  return catenary_sim::load_scene_string(s.str(), overrides);
}

}  // namespace test_scenes
