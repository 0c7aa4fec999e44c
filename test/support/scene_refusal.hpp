// A scene that must be refused, and the field its message must name (gtest); what a scene file
// with overrides is refused with. Header-only.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include <vector>

#include "catenary_sim/core/scene/scene.hpp"
#include "catenary_sim/core/simulation.hpp"

namespace test_scenes {

inline void expect_refused(const std::string& yaml, const std::string& field) {
  try {
    catenary_sim::load_scene_string(yaml);
    ADD_FAILURE() << "accepted; expected a refusal naming " << field;
  } catch (const catenary_sim::SceneError& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
  }
}

// The message a scene that `load` reads is refused with, when it is read or built into a
// simulation; "" when it is accepted.
template <class Load>
std::string refusal(Load&& load) {
  try {
    catenary_sim::Simulation sim(load());
  } catch (const catenary_sim::SceneError& e) {
    return e.what();
  }
  return "";
}

// The same for a scene file with `overrides` (--set style).
inline std::string refusal_of(const std::string& file, const std::vector<std::string>& overrides) {
  return refusal([&] { return catenary_sim::load_scene_file(file, overrides); });
}

// The same for a scene given as YAML text.
inline std::string refusal_of_yaml(const std::string& yaml, const std::vector<std::string>& overrides = {}) {
  return refusal([&] { return catenary_sim::load_scene_string(yaml, overrides); });
}

}  // namespace test_scenes
