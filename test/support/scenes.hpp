// Where the tests (and bench/) find the source tree, the shipped scenes and the programs under
// test, and the scenes several tests build from them. One place, so that a test needs no path
// or scene of its own. Header-only.
#pragma once

#include <cstdint>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "catenary_sim/core/scene/scene.hpp"

// The source tree and the devel space's programs: the build defines both for the tests.
#ifndef CATENARY_SIM_SOURCE_DIR
#define CATENARY_SIM_SOURCE_DIR "."
#endif
#ifndef CATENARY_SIM_DEVEL_LIB
#define CATENARY_SIM_DEVEL_LIB "."
#endif

namespace test_scenes {

// Built from literals alone (no other namespace-scope string), so a test's own globals can use
// them whatever the order of initialisation.
inline const std::string kSourceDir = CATENARY_SIM_SOURCE_DIR;
inline const std::string kConfigDir = CATENARY_SIM_SOURCE_DIR "/config/";
inline const std::string kDevelLib = CATENARY_SIM_DEVEL_LIB;

// The shipped scenes.
inline const std::string kReference = CATENARY_SIM_SOURCE_DIR "/config/reference_55m.yaml";
inline const std::string kReference3d = CATENARY_SIM_SOURCE_DIR "/config/reference_55m_3d.yaml";
inline const std::string kReferenceEndless = CATENARY_SIM_SOURCE_DIR "/config/reference_55m_endless.yaml";
inline const std::string kReferenceHil = CATENARY_SIM_SOURCE_DIR "/config/reference_55m_hil.yaml";
inline const std::string kReferenceTwoHeads = CATENARY_SIM_SOURCE_DIR "/config/reference_55m_two_heads.yaml";
inline const std::string kReferenceTwoPantographs =
    CATENARY_SIM_SOURCE_DIR "/config/reference_55m_two_pantographs.yaml";
inline const std::string kReferenceStitched = CATENARY_SIM_SOURCE_DIR "/config/reference_55m_stitched.yaml";
inline const std::string kReferenceTwoSections = CATENARY_SIM_SOURCE_DIR "/config/reference_55m_two_sections.yaml";
inline const std::string kReferenceStitched3d = CATENARY_SIM_SOURCE_DIR "/config/reference_55m_stitched_3d.yaml";
inline const std::string kCompound = CATENARY_SIM_SOURCE_DIR "/config/compound_catenary.yaml";
inline const std::string kReferenceHingedArms = CATENARY_SIM_SOURCE_DIR "/config/reference_55m_hinged_arms.yaml";

// A shipped scene of one section of equal spans as an endless line: its `line.span_count` left
// out, `line.endless: true` (give numerics.window among the overrides): its YAML text, and the
// scene read from it.
inline std::string endless_yaml(const std::string& path) {
  YAML::Node root = YAML::LoadFile(path);
  root["line"].remove("span_count");
  root["line"]["endless"] = true;
  std::ostringstream yaml;
  yaml << root;
  return yaml.str();
}
inline catenary_sim::Scene endless_scene(const std::string& path, const std::vector<std::string>& overrides) {
  return catenary_sim::load_scene_string(endless_yaml(path), overrides);
}
inline const std::string kCalpeExample = CATENARY_SIM_SOURCE_DIR "/config/calpe_example.yaml";

// A shipped scene by its file name (config/<file>).
inline std::string scene_path(const std::string& file) { return kConfigDir + file; }

// A program of the devel space by name (simulate_pass, catenary_sim_node, ...).
inline std::string program(const std::string& name) { return kDevelLib + "/" + name; }
// A Python node of the package (run from its source, as rosrun and roslaunch find it).
inline std::string script(const std::string& name) { return kSourceDir + "/scripts/" + name; }

// A shipped scene (config/<file>) as YAML, changed by `edit`, then loaded with `overrides`: for
// what --set cannot say (a key removed, a section added, a pantograph's type changed).
inline catenary_sim::Scene edited_scene(const std::string& file, const std::function<void(YAML::Node&)>& edit,
                                        const std::vector<std::string>& overrides = {}) {
  YAML::Node root = YAML::LoadFile(scene_path(file));
  edit(root);
  std::stringstream s;
  s << root;
  return catenary_sim::load_scene_string(s.str(), overrides);
}

// The reference catenary as one section of `span_count` 55 m spans with `contact_wires` contact
// wires on the same stations (two: packed as two lanes and one with the messenger).
inline catenary_sim::Scene reference_with_contact_wires(int contact_wires, int span_count,
                                                        const std::function<void(YAML::Node&)>& edit,
                                                        const std::vector<std::string>& overrides = {}) {
  return edited_scene(
      "reference_55m.yaml",
      [&](YAML::Node& root) {
        root["line"].remove("span_length");
        root["line"].remove("span_count");
        YAML::Node sec;
        sec["span_length"] = 55.0;
        sec["span_count"] = span_count;
        sec["contact_wire_count"] = contact_wires;
        root["sections"].push_back(sec);
        edit(root);
      },
      overrides);
}

// The reference catenary as one 6-span section with a twin contact wire: three wires on the same
// stations, packed as two lanes and one.
inline catenary_sim::Scene twin_contact_wire(const std::vector<std::string>& overrides) {
  return reference_with_contact_wires(2, 6, [](YAML::Node&) {}, overrides);
}

// A 20 m/s wind with 15 % turbulence (von Karman length 50 m, Davenport decay 10, up to 5 Hz)
// on points `spacing` m apart: gusts strong enough to move the wires, a field small enough to
// draw fast.
inline catenary_sim::WindSpec gusty_wind(std::uint64_t seed, double spacing = 5.0) {
  catenary_sim::WindSpec w;
  w.speed = 20.0;
  catenary_sim::TurbulenceSpec t;
  t.intensity = 0.15;
  t.length_scale = 50.0;
  t.coherence_decay = 10.0;
  t.max_frequency = 5.0;
  t.spacing = spacing;
  t.seed = seed;
  w.turbulence = t;
  return w;
}

// `file` with its first pantograph repeated `count` times, 20 m apart (names p0, p1, ...), written
// to `path` (e.g. five external pantographs, more than a HIL packet carries); returns `path`.
inline std::string with_pantograph_copies(const std::string& file, int count, const std::string& path) {
  YAML::Node root = YAML::LoadFile(file);
  const YAML::Node first = YAML::Clone(root["pantographs"][0]);
  root["pantographs"] = YAML::Node(YAML::NodeType::Sequence);
  for (int i = 0; i < count; ++i) {
    YAML::Node p = YAML::Clone(first);
    p["name"] = "p" + std::to_string(i);
    p["position"] = 20.0 * i;
    root["pantographs"].push_back(p);
  }
  std::ofstream(path) << YAML::Dump(root) << "\n";
  return path;
}

}  // namespace test_scenes
