// Every class of bad scene input gives an error naming the field, the value and what is allowed;
// rejected commands leave the state as it was.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "catenary_sim/core/simulation.hpp"

#ifndef CATENARY_SIM_SOURCE_DIR
#define CATENARY_SIM_SOURCE_DIR "."
#endif

using namespace catenary_sim;

namespace {

const std::string kReference = CATENARY_SIM_SOURCE_DIR "/config/reference_55m.yaml";

std::string error_of(const std::vector<std::string>& overrides) {
  try {
    Simulation sim(load_scene_file(kReference, overrides));
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

std::string error_of_yaml(const std::string& yaml) {
  try {
    Simulation sim(load_scene_string(yaml));
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

std::string reference_without(const std::string& key) {
  YAML::Node root = YAML::LoadFile(kReference);
  root.remove(key);
  std::stringstream s;
  s << root;
  return s.str();
}

#define EXPECT_MENTIONS(msg, ...)                                                   \
  do {                                                                              \
    const std::string m_ = (msg);                                                   \
    ASSERT_FALSE(m_.empty()) << "no error raised";                                  \
    for (const char* part : {__VA_ARGS__}) EXPECT_NE(m_.find(part), std::string::npos) << "'" << part << "' not in: " << m_; \
  } while (0)

}  // namespace

TEST(SceneErrors, ReferenceSceneLoads) { EXPECT_EQ(error_of({}), ""); }

TEST(SceneErrors, OutOfRangeNamesFieldValueAndRange) {
  EXPECT_MENTIONS(error_of({"contact_wire.tension=-5"}), "contact_wire.tension", "-5", "allowed range (0, ");
  EXPECT_MENTIONS(error_of({"contact_wire.tension=.inf"}), "contact_wire.tension", "allowed range");
  EXPECT_MENTIONS(error_of({"contact_wire.linear_mass=.nan"}), "contact_wire.linear_mass", "allowed range");
  EXPECT_MENTIONS(error_of({"damping.beta=1"}), "damping.beta", "1", "[0, 0.1]");
  EXPECT_MENTIONS(error_of({"pantographs.0.static_uplift=-1"}), "pantographs[0].static_uplift", "-1", "allowed range");
}

// The report's fields (issue 15): limits absent by default, each checked like the others.
TEST(SceneErrors, OutputLimitsAndMeasurementFields) {
  EXPECT_EQ(error_of({"output.allowed_uplift=0.12", "output.max_stat_force=350", "output.min_stat_force=0",
                      "output.max_contact_loss_percent=0.1", "output.sensor_bandwidth=40", "output.dropper_series=true"}),
            "");
  EXPECT_MENTIONS(error_of({"output.allowed_uplift=0"}), "output.allowed_uplift", "0", "(0, 10]");
  EXPECT_MENTIONS(error_of({"output.allowed_uplift=-0.1"}), "output.allowed_uplift", "-0.1", "allowed range");
  EXPECT_MENTIONS(error_of({"output.max_stat_force=.nan"}), "output.max_stat_force", "allowed range");
  EXPECT_MENTIONS(error_of({"output.max_contact_loss_percent=101"}), "output.max_contact_loss_percent", "101", "[0, 100]");
  EXPECT_MENTIONS(error_of({"output.min_stat_force=low"}), "output.min_stat_force", "'low'", "a number");
  EXPECT_MENTIONS(error_of({"output.sensor_bandwidth=0"}), "output.sensor_bandwidth", "(0, ");
  EXPECT_MENTIONS(error_of({"output.dropper_series=sometimes"}), "output.dropper_series", "'sometimes'", "true or false");
  EXPECT_MENTIONS(error_of({"output.allowed_uplfit=0.1"}), "output.allowed_uplfit", "unknown field");
  const Scene s = load_scene_file(kReference);
  EXPECT_FALSE(s.output.allowed_uplift || s.output.max_stat_force || s.output.min_stat_force ||
               s.output.max_contact_loss_percent);
  EXPECT_EQ(s.output.sensor_bandwidth, 20.0);
  EXPECT_FALSE(s.output.dropper_series);
}

TEST(SceneErrors, NotANumber) {
  EXPECT_MENTIONS(error_of({"contact_wire.linear_mass=heavy"}), "contact_wire.linear_mass", "'heavy'", "a number");
  EXPECT_MENTIONS(error_of({"droppers.positions=7"}), "droppers.positions", "a list of numbers");
}

TEST(SceneErrors, MissingRequiredField) {
  EXPECT_MENTIONS(error_of_yaml(reference_without("contact_wire")), "contact_wire", "(missing)", "required");
  EXPECT_MENTIONS(error_of({"contact_wire.tension=null"}), "contact_wire.tension", "(missing)", "required");
}

TEST(SceneErrors, UnknownFieldIsATypo) {
  EXPECT_MENTIONS(error_of({"contact_wire.tensoin=20000"}), "contact_wire.tensoin", "unknown field");
  EXPECT_MENTIONS(error_of({"numerics.element_lenght=0.1"}), "numerics.element_lenght", "unknown field");
}

TEST(SceneErrors, BadChoice) {
  EXPECT_MENTIONS(error_of({"numerics.rotary_inertia=exact"}), "numerics.rotary_inertia", "'exact'", "condensed", "lumped");
  EXPECT_MENTIONS(error_of({"pantographs.0.type=magnetic"}), "pantographs[0].type", "'magnetic'", "lumped", "moving_force");
}

TEST(SceneErrors, PantographChainLengths) {
  EXPECT_MENTIONS(error_of({"pantographs.0.stiffness=[7000, 15500]"}), "pantographs[0].stiffness", "2 values", "one per mass (3)");
  EXPECT_MENTIONS(error_of({"pantographs.0.stiffness=[0, 15500, 160]"}), "pantographs[0].stiffness[0]", "must be > 0");
  EXPECT_MENTIONS(error_of({"pantographs.0.masses=[]"}), "pantographs[0].masses", "at least one mass");
}

TEST(SceneErrors, DropperGeometry) {
  EXPECT_MENTIONS(error_of({"droppers.positions=[4.5, 60]"}), "droppers.positions", "60", "strictly inside the span (0, 55)");
  EXPECT_MENTIONS(error_of({"droppers.positions=[10, 5]"}), "droppers.positions", "5", "increasing");
  EXPECT_MENTIONS(error_of_yaml(reference_without("messenger")), "droppers", "messenger");
  // A presag the droppers cannot reach: the messenger would hang below the contact wire.
  EXPECT_MENTIONS(error_of({"contact_wire.presag=0.9", "line.encumbrance=0.3"}), "droppers", "x = ", "m");
}

TEST(SceneErrors, PresagNeedsDroppers) {
  EXPECT_MENTIONS(error_of_yaml(reference_without("droppers")), "contact_wire.presag", "0.055", "without droppers");
}

TEST(SceneErrors, TimeStepAboveStabilityLimitIsRefusedWithTheLimit) {
  const std::string e = error_of({"numerics.dt=0.005"});
  EXPECT_MENTIONS(e, "numerics.dt", "0.005", "stability limit", "dt <= ");
}

TEST(SceneErrors, SectionsAndMeshing) {
  EXPECT_MENTIONS(error_of({"output.analysis_spans=[5, 20]"}), "output.analysis_spans", "[5, 20]", "span count (10)");
  EXPECT_MENTIONS(error_of({"numerics.element_length=8", "line.span_length=5", "droppers.positions=[2.5]"}), "numerics.element_length", "8", "shortest span");
  EXPECT_MENTIONS(error_of({"line.span_count=2.5"}), "line.span_count", "2.5", "whole number");
  EXPECT_MENTIONS(error_of({"train.end=1000"}), "train.end", "1000", "line length 550");
}

TEST(SceneErrors, DuplicatePantographNames) {
  YAML::Node root = YAML::LoadFile(kReference);
  YAML::Node p2 = YAML::Clone(root["pantographs"][0]);
  root["pantographs"].push_back(p2);
  std::stringstream s;
  s << root;
  EXPECT_MENTIONS(error_of_yaml(s.str()), "pantographs[1].name", "'leading'", "unique");
}

TEST(SceneErrors, FilesSyntaxAndOverrides) {
  EXPECT_MENTIONS([] {
    try { load_scene_file("/nonexistent/scene.yaml"); } catch (const SceneError& e) { return std::string(e.what()); }
    return std::string();
  }(), "/nonexistent/scene.yaml", "cannot be opened");
  EXPECT_MENTIONS(error_of_yaml("line: [unclosed"), "not valid YAML");
  EXPECT_MENTIONS(error_of_yaml("- just\n- a list\n"), "YAML map");
  EXPECT_MENTIONS(error_of({"no_equals_sign"}), "no_equals_sign", "key.path=value");
  EXPECT_MENTIONS(error_of({"pantographs.7.static_uplift=1"}), "index 7 out of range");
}

TEST(Commands, RejectedCommandsLeaveTheStateAsItWas) {
  Simulation sim(load_scene_file(kReference));
  for (int i = 0; i < 50; ++i) sim.step();
  const State before = sim.state();
  std::string err;
  for (double bad : {std::nan(""), double(INFINITY), -1.0, 1e4}) {
    EXPECT_FALSE(sim.set_target_speed(bad, &err));
    EXPECT_NE(err.find("m/s rejected: allowed 0 to"), std::string::npos) << err;
    EXPECT_FALSE(sim.set_uplift(-1, bad, &err));
    EXPECT_NE(err.find("N rejected: allowed 0 to"), std::string::npos) << err;
  }
  EXPECT_FALSE(sim.set_uplift(3, 100.0, &err));
  EXPECT_NE(err.find("pantograph index 3"), std::string::npos) << err;
  EXPECT_FALSE(sim.set_max_acceleration(-2.0, &err));
  const State& after = sim.state();
  EXPECT_EQ(after.target_speed, before.target_speed);
  EXPECT_EQ(after.max_acceleration, before.max_acceleration);
  EXPECT_EQ(after.uplift, before.uplift);
  EXPECT_EQ(0, std::memcmp(after.u.data(), before.u.data(), sizeof(double) * after.u.size()));
  // and accepted ones take effect
  EXPECT_TRUE(sim.set_uplift(-1, 120.0, &err));
  EXPECT_EQ(sim.state().uplift[0], 120.0);
}
