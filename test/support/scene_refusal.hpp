// A scene that must be refused, and the field its message must name (gtest). Header-only.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "catenary_sim/core/scene/scene.hpp"

namespace test_scenes {

inline void expect_refused(const std::string& yaml, const std::string& field) {
  try {
    catenary_sim::load_scene_string(yaml);
    ADD_FAILURE() << "accepted; expected a refusal naming " << field;
  } catch (const catenary_sim::SceneError& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
  }
}

}  // namespace test_scenes
