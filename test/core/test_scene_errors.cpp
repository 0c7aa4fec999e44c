// Every class of bad scene input gives an error naming the field, the value and what is allowed;
// rejected commands leave the state as it was.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "catenary_sim/core/simulation.hpp"
#include "../support/scene_refusal.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

namespace {

using test_scenes::kReference;

std::string error_of(const std::vector<std::string>& overrides) { return test_scenes::refusal_of(kReference, overrides); }

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
  // Stations are finite; a start of -0 (the front at the line's start less no offset) shows as 0.
  EXPECT_MENTIONS(error_of({"train.end=.inf"}), "train.end", "[-1000000000, 1000000000]");
  const std::string before = error_of({"train.end=-5"});
  EXPECT_MENTIONS(before, "train.end", "-5", "train.start (0 m)");
  EXPECT_EQ(before.find("-0 m"), std::string::npos) << before;
}

// The report's fields: limits absent by default, each checked like the others.
TEST(SceneErrors, OutputLimitsAndMeasurementFields) {
  EXPECT_EQ(error_of({"output.allowed_uplift=0.12", "output.max_stat_force=350", "output.min_stat_force=0",
                      "output.max_contact_loss_percent=0.1", "output.sensor_bandwidth=40", "output.dropper_series=true"}),
            "");
  EXPECT_MENTIONS(error_of({"output.allowed_uplift=0"}), "output.allowed_uplift", "0", "(0, 10]");
  EXPECT_MENTIONS(error_of({"output.allowed_uplift=-0.1"}), "output.allowed_uplift", "-0.1", "allowed range");
  EXPECT_MENTIONS(error_of({"output.max_stat_force=.nan"}), "output.max_stat_force", "allowed range");
  EXPECT_MENTIONS(error_of({"output.max_contact_loss_percent=101"}), "output.max_contact_loss_percent", "101", "[0, 100]");
  EXPECT_MENTIONS(error_of({"output.min_stat_force=low"}), "output.min_stat_force", "'low'", "a number");
  EXPECT_MENTIONS(error_of({"output.sensor_bandwidth=0"}), "output.sensor_bandwidth", "[0.1, ");
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
  // Text that spells a number is still text: quoted, in an override or a file, and in a list.
  EXPECT_MENTIONS(error_of({"contact_wire.tension=\"20000\""}), "contact_wire.tension", "'20000' (in quotes, so text)");
  EXPECT_MENTIONS(error_of({"contact_wire.tension='2e4 '"}), "contact_wire.tension", "'2e4 '", "without quotes");
  EXPECT_MENTIONS(error_of({"droppers.positions=[4.5, '10.25']"}), "droppers.positions[1]", "in quotes");
  EXPECT_EQ(error_of({"contact_wire.tension=20000"}), "");
  // A tag says what a scalar is: !!str makes text of it (not the number it spells), YAML's
  // number tags leave it a number.
  EXPECT_MENTIONS(error_of({"contact_wire.tension=!!str 20000"}), "contact_wire.tension", "tagged", "written plain");
  EXPECT_MENTIONS(error_of({"contact_wire.tension=!tension 20000"}), "contact_wire.tension", "tagged");
  EXPECT_EQ(error_of({"contact_wire.tension=!!float 20000"}), "");
  EXPECT_EQ(error_of({"contact_wire.tension=!!int 20000"}), "");
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
  // A list entry as the messages name it (pantographs[0]) sets what pantographs.0 does; an index
  // in brackets that is not digits after a name is refused.
  EXPECT_EQ(load_scene_file(kReference, {"pantographs[0].static_uplift=150"}).pantographs[0].static_uplift, 150.0);
  EXPECT_EQ(load_scene_file(test_scenes::kReference3d, {"stagger.contact_wire[1]=-0.25"}).stagger->contact_wire.at(1), -0.25);
  EXPECT_MENTIONS(error_of({"pantographs[7].static_uplift=1"}), "index 7 out of range");
  for (const char* bad : {"pantographs[x].static_uplift=1", "pantographs[].static_uplift=1", "[0].name=a",
                          "pantographs[0]static_uplift=1", "pantographs.[0].static_uplift=1", "pantographs[0=1"})
    EXPECT_MENTIONS(error_of({bad}), "list index in brackets");
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

// A refused command's value is printed whole: one just past a limit must not read as the limit
// ("1000 N rejected: allowed 0 to 1000 N"). The number in the message reads back as the value.
TEST(Commands, AValueJustPastALimitIsPrintedWhole) {
  Simulation sim(load_scene_file(kReference));
  std::string err;
  auto value_in = [&](const std::string& before) { return std::stod(err.substr(err.find(before) + before.size())); };
  const double uplift = std::nextafter(Simulation::kMaxUplift, 2.0 * Simulation::kMaxUplift);
  EXPECT_FALSE(sim.set_uplift(-1, uplift, &err));
  EXPECT_EQ(value_in("uplift force "), uplift) << err;
  EXPECT_FALSE(sim.set_max_acceleration(20.0000001, &err));
  EXPECT_EQ(value_in("max acceleration "), 20.0000001) << err;
  const double speed = std::nextafter(150.0, 200.0);  // above the 540 km/h bound of every scene
  EXPECT_FALSE(sim.set_target_speed(speed, &err));
  EXPECT_EQ(value_in("train speed "), speed) << err;
}

namespace {

using test_scenes::kReference3d;

std::string error_of_3d(const std::vector<std::string>& overrides) { return test_scenes::refusal_of(kReference3d, overrides); }

// The reference scene's text with `line` put in place of its first line ("name: ...").
std::string reference_with_first_line(const std::string& line) {
  std::ifstream in(kReference);
  std::stringstream s;
  s << in.rdbuf();
  std::string text = s.str();
  const std::size_t at = text.find("\nname:");
  const std::size_t end = text.find('\n', at + 1);
  return text.substr(0, at + 1) + line + text.substr(end);
}

}  // namespace

// yaml-cpp shares an aliased node: an alias inside its own anchor is a node that contains itself,
// and every walk over the tree would recurse without end (a stack overflow).
TEST(SceneErrors, AnchorThatContainsItselfIsRefused) {
  EXPECT_MENTIONS(error_of_yaml(reference_with_first_line("name: &r [*r]")), "'*r'", "its own anchor", "line ");
  EXPECT_MENTIONS(error_of({"name=&a [*a]"}), "name=&a [*a]", "'*a'", "its own anchor");
  EXPECT_MENTIONS(error_of({"numerics=&n {dt: *n}"}), "numerics", "'*n'", "its own anchor");
}

// Aliases of aliases multiply: 9 levels of 9 are 9^9 visits from a few hundred bytes.
TEST(SceneErrors, AliasExpansionIsBounded) {
  std::string bomb = "a0: &a0 [1, 2, 3, 4, 5, 6, 7, 8, 9]\n";
  for (int i = 1; i < 10; ++i) {
    bomb += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [";
    for (int k = 0; k < 9; ++k) bomb += (k ? ", *a" : "*a") + std::to_string(i - 1);
    bomb += "]\n";
  }
  const std::string budget = std::to_string(kMaxAliasExpansion);
  EXPECT_MENTIONS(error_of_yaml(reference_with_first_line("name: bomb\n" + bomb)), "aliases expand to more than",
                  budget.c_str());
  // The same in an override's value: [&b0 [1..9], &b1 [*b0 x 9], ..., &b9 [*b8 x 9]].
  std::string flow = "[&b0 [1, 2, 3, 4, 5, 6, 7, 8, 9]";
  for (int i = 1; i < 10; ++i) {
    flow += ", &b" + std::to_string(i) + " [";
    for (int k = 0; k < 9; ++k) flow += (k ? ", *b" : "*b") + std::to_string(i - 1);
    flow += "]";
  }
  EXPECT_MENTIONS(error_of({"name=" + flow + "]"}), "override 'name=", "aliases expand to more than");
  // An anchor used for what it is for, a repeated value, reads as the value written out.
  const std::string text = reference_with_first_line("name: reference_55m");
  std::string aliased = text;
  aliased.replace(aliased.find("  tension: 22000.0"), 18, "  tension: &t 22000.0");
  aliased.replace(aliased.find("  tension: 16000.0"), 18, "  tension: *t");
  const Scene a = load_scene_string(aliased), b = load_scene_string(text, {"messenger.tension=22000.0"});
  EXPECT_EQ(a.messenger->tension, b.messenger->tension);
  EXPECT_EQ(a.messenger->tension, a.contact_wire.tension);
}

TEST(SceneErrors, SecondDocumentIsRefused) {
  const std::string text = reference_with_first_line("name: reference_55m");
  EXPECT_MENTIONS(error_of_yaml(text + "---\ntrain: {speed_kmh: 100}\n"), "second YAML document", "line ");
  EXPECT_EQ(error_of_yaml(text + "---\n"), "");  // an empty document after the scene holds nothing to ignore
}

// A bin far below the head's width asked for more bins than memory holds (1e-8 m: 2e8 bins, a
// bad_alloc after the whole pass; 1e-300: an int overflow, one bin).
TEST(SceneErrors, HistogramBinsAreBounded) {
  for (const char* bin : {"1e-8", "1e-300"})
    EXPECT_MENTIONS(error_of_3d({std::string("pantograph_head.histogram_bin=") + bin}), "pantograph_head.histogram_bin",
                    "allowed [", "bins across pantograph_head.horn_width");
  // At the bound: horn_width / bin = kMaxHistogramBins bins.
  EXPECT_EQ(error_of_3d({"pantograph_head.histogram_bin=" + std::to_string(1.95 / kMaxHistogramBins)}), "");
}

// The turbulent field's points over the line: 550 m / 1e-9 m overflows the point count's int,
// 550 m / 1e-6 m asks for far more than memory; both are refused naming the spacing.
TEST(SceneErrors, TurbulencePointsAreBounded) {
  for (const auto& [spacing, shown] : {std::pair{"1e-9", "1e-09"}, {"3e-9", "3e-09"}, {"1e-6", "1e-06"}})
    EXPECT_MENTIONS(error_of_3d({std::string("wind.turbulence.spacing=") + spacing}), "wind.turbulence.spacing", shown,
                    "field points over the");
  const Scene s = load_scene_file(kReference3d);
  // The field's memory is part of the model's estimate (it grows as the points).
  Scene fine = s;
  fine.wind->turbulence->spacing = 0.5;
  EXPECT_GT(estimate_wind_field_bytes(s), 0.0);
  // Ten times the points at 0.5 m as at 5 m: the points' series dominate the field's estimate, so it
  // grows nearly tenfold (the synthesis's and the FFT's buffers, a fixed part, do not grow).
  EXPECT_GT(wind_field_points(fine), 9.0 * wind_field_points(s));
  EXPECT_GT(estimate_wind_field_bytes(fine), 5.0 * estimate_wind_field_bytes(s));
  EXPECT_EQ(estimate_model_bytes(fine) - estimate_model_bytes(s), estimate_wind_field_bytes(fine) - estimate_wind_field_bytes(s));
  // An endless line holds only its block's points (generated as the block moves): the length of
  // the pass is no reason to refuse a spacing, 900 km at 5 m being 180,000 points along the way.
  const std::string endless = test_scenes::kReferenceEndless;
  EXPECT_NO_THROW(load_scene_file(endless, {"train.end=900000", "stagger.contact_wire=[0.3, -0.3]", "wind.speed=20",
                                            "wind.turbulence.intensity=0.15"}));
  std::string fine_endless;
  try {
    load_scene_file(endless, {"train.end=900000", "stagger.contact_wire=[0.3, -0.3]", "wind.speed=20",
                              "wind.turbulence.intensity=0.15", "wind.turbulence.spacing=0.01"});
  } catch (const SceneError& e) {
    fine_endless = e.what();
  }
  EXPECT_MENTIONS(fine_endless, "wind.turbulence.spacing", "0.01", "holds at once");
}

// The speed limit: below the contact wire's wave speed c = sqrt(T / rhoA), computed here from the
// scene's own wire (22 kN on 1.35 kg/m: 127.66 m/s).
TEST(SceneErrors, SupercriticalSpeedIsRefusedEverywhere) {
  const double c = std::sqrt(22000.0 / 1.35);
  const TrainSpeedLimit limit = train_speed_limit(load_scene_file(kReference));
  EXPECT_NEAR(limit.wave_speed, c, 1e-9 * c);
  EXPECT_TRUE(limit.below_wave_speed);
  EXPECT_MENTIONS(error_of({"train.speed_kmh=800"}), "train.speed_kmh", "800", "wave speed", "allow_supercritical");
  EXPECT_MENTIONS(error_of({"train.speed_kmh=null", "train.speed=" + std::to_string(1.0001 * c)}), "train.speed_kmh",
                  "wave speed");
  EXPECT_EQ(error_of({"train.speed_kmh=null", "train.speed=" + std::to_string(0.99 * c)}), "");
  // Beyond the ceiling even with the opt-in.
  EXPECT_MENTIONS(error_of({"train.speed_kmh=541", "numerics.allow_supercritical=true"}), "train.speed_kmh", "541",
                  "0 to 150 m/s (540 km/h)");
  // A Scene changed in code after loading meets the same limit when it is run.
  Scene s = load_scene_file(kReference);
  s.train_speed = 1.01 * c;
  EXPECT_THROW(Simulation{s}, SceneError);
  // The explicit opt-in runs it, up to the ceiling.
  EXPECT_EQ(error_of({"train.speed_kmh=500", "numerics.allow_supercritical=true"}), "");
  EXPECT_MENTIONS(error_of({"numerics.allow_supercritical=maybe"}), "numerics.allow_supercritical", "true or false");
  // Commands: refused beyond the wave speed, the state as it was; accepted below it.
  Simulation sim(load_scene_file(kReference));
  for (int i = 0; i < 20; ++i) sim.step();
  const State before = sim.state();
  std::string err;
  for (double v : {c, 1.2 * c, 149.0}) {
    EXPECT_FALSE(sim.set_target_speed(v, &err)) << v;
    EXPECT_NE(err.find("wave speed"), std::string::npos) << err;
  }
  EXPECT_EQ(sim.state().target_speed, before.target_speed);
  EXPECT_TRUE(sim.set_target_speed(0.9 * c, &err)) << err;
  Simulation super(load_scene_file(kReference, {"numerics.allow_supercritical=true"}));
  EXPECT_TRUE(super.set_target_speed(1.1 * c, &err)) << err;
  EXPECT_FALSE(super.set_target_speed(kMaxTrainSpeed * 1.0001, &err));
}

// Fields that can never act where they are given are refused, not silently ignored.
TEST(SceneErrors, FieldsThatCannotActAreRefused) {
  EXPECT_MENTIONS(error_of_3d({"stagger.messenger=[]"}), "stagger.messenger", "empty list", "leave the field out");
  // gust_lead needs a turbulent wind and the moving window.
  EXPECT_MENTIONS(error_of({"numerics.gust_lead=5"}), "numerics.gust_lead", "5", "wind.turbulence", "numerics.window");
  EXPECT_MENTIONS(error_of_3d({"numerics.gust_lead=5"}), "numerics.gust_lead", "numerics.window");
  EXPECT_EQ(error_of_3d({"numerics.gust_lead=5", "numerics.window=auto"}), "");
  // So does how the lead is stepped; implicit is one solve per wire, which a stitch wire's clamps
  // would join to the messenger's.
  EXPECT_MENTIONS(error_of_3d({"numerics.gust_lead_step=implicit"}), "numerics.gust_lead_step", "'implicit'",
                  "numerics.window");
  EXPECT_MENTIONS(error_of({"numerics.gust_lead_step=explicit", "numerics.window=auto"}), "numerics.gust_lead_step",
                  "wind.turbulence");
  EXPECT_MENTIONS(error_of_3d({"numerics.gust_lead_step=sideways", "numerics.window=auto"}), "numerics.gust_lead_step",
                  "'sideways'", "implicit", "explicit");
  EXPECT_MENTIONS(error_of_3d({"numerics.gust_lead_step=[implicit]", "numerics.window=auto"}),
                  "numerics.gust_lead_step", "not a scalar");
  for (const char* step : {"implicit", "explicit"})
    EXPECT_EQ(error_of_3d({std::string("numerics.gust_lead_step=") + step, "numerics.window=auto"}), "") << step;
  const std::string stitched = test_scenes::refusal_of(test_scenes::scene_path("reference_55m_stitched_3d.yaml"),
                                                       {"numerics.window=auto", "numerics.gust_lead_step=implicit"});
  EXPECT_MENTIONS(stitched, "numerics.gust_lead_step", "'implicit'", "stitch wires", "explicit");
  // A strip's working width needs a 3-D line.
  EXPECT_MENTIONS(error_of({"pantographs.0.collectors=[{offset: 0.0, working_width: 1.0}]"}),
                  "pantographs[0].collectors[0].working_width", "only on a 3-D line");
  EXPECT_EQ(error_of_3d({"pantographs.0.collectors=[{offset: 0.0, working_width: 1.0}]"}), "");
  // An overlap needs two sections; dropper positions for transition spans need a line that has
  // some. (A given support_rise takes precedence over design_force, which a study of the rise on a
  // scene that gives the force relies on.)
  EXPECT_MENTIONS(error_of({"overlap={spans: 1, support_rise: 0.1}"}), "'overlap'", "one section", "two or more");
  EXPECT_MENTIONS(error_of({"droppers.transition_positions=[5.0]"}), "droppers.transition_positions", "one section");
  // A messenger without droppers would hang apart from the contact wire.
  EXPECT_MENTIONS(error_of({"droppers=null", "contact_wire.presag=0"}), "'messenger'", "without droppers");
}

// numerics.supports and numerics.droppers: a value of the two, and implicit only where the explicit
// half-step takes it; explicit unless asked, but for the fast preset on a 2-D line (where the scheme
// takes them), whose default is implicit.
TEST(SceneErrors, SpringsAtTheMiddleOnlyWithTheHalfStep) {
  for (const char* field : {"numerics.supports", "numerics.droppers"}) {
    SCOPED_TRACE(field);
    EXPECT_MENTIONS(error_of({std::string(field) + "=trapezoidal"}), field, "trapezoidal", "explicit", "implicit");
    EXPECT_MENTIONS(error_of({std::string(field) + "=implicit", "numerics.damping=centred"}), field, "implicit", "centred");
    EXPECT_MENTIONS(error_of({std::string(field) + "=implicit", "numerics.integrator=implicit"}), field, "implicit integrator");
    EXPECT_EQ(error_of({std::string(field) + "=implicit"}), "");
  }
  auto numerics = [](const std::vector<std::string>& o) { return load_scene_file(kReference, o).numerics; };
  for (const char* preset : {"balanced", "accurate", "reference"}) {
    const NumericsSpec n = numerics({std::string("numerics.preset=") + preset});
    EXPECT_EQ(n.supports, SpringStep::kExplicit) << preset;
    EXPECT_EQ(n.droppers, SpringStep::kExplicit) << preset;
  }
  EXPECT_EQ(numerics({"numerics.supports=implicit"}).supports, SpringStep::kImplicit);
  EXPECT_EQ(numerics({"numerics.droppers=implicit"}).droppers, SpringStep::kImplicit);
  // The fast preset: both at the middle on a 2-D line, both at q_n on a 3-D one, and where a field
  // is given, as given; with the centred damping or the implicit integrator, at q_n without a refusal.
  EXPECT_EQ(numerics({"numerics.preset=fast"}).supports, SpringStep::kImplicit);
  EXPECT_EQ(numerics({"numerics.preset=fast"}).droppers, SpringStep::kImplicit);
  const NumericsSpec lateral = load_scene_file(test_scenes::kConfigDir + "reference_55m_3d.yaml", {"numerics.preset=fast"}).numerics;
  EXPECT_EQ(lateral.supports, SpringStep::kExplicit);
  EXPECT_EQ(lateral.droppers, SpringStep::kExplicit);
  EXPECT_EQ(numerics({"numerics.preset=fast", "numerics.droppers=explicit"}).droppers, SpringStep::kExplicit);
  // A 3-D line's lateral plane loads its droppers with their tension at q_n: refused there.
  EXPECT_MENTIONS(error_of_3d({"numerics.droppers=implicit"}), "numerics.droppers", "implicit", "3-D line");
  EXPECT_EQ(error_of_3d({"numerics.supports=implicit"}), "");
  EXPECT_EQ(error_of_3d({"numerics.preset=fast", "numerics.supports=implicit"}), "");  // droppers: the preset's q_n
  for (const char* other : {"numerics.damping=centred", "numerics.integrator=implicit"}) {
    EXPECT_EQ(error_of({"numerics.preset=fast", other}), "") << other;
    EXPECT_EQ(numerics({"numerics.preset=fast", other}).droppers, SpringStep::kExplicit) << other;
  }
}

// The centred step's estimate is no bound at the estimate itself (the reference diverged at a
// safety factor of 0.99 with it): a dt that close is refused up front, not found by a divergence.
TEST(SceneErrors, CentredStepKeepsItsMargin) {
  EXPECT_MENTIONS(error_of({"numerics.damping=centred", "numerics.safety_factor=1"}), "numerics.safety_factor", "1",
                  "numerics.damping: centred");
  EXPECT_EQ(error_of({"numerics.damping=centred", "numerics.safety_factor=0.95"}), "");
  EXPECT_EQ(error_of({"numerics.safety_factor=1"}), "");  // the half step's estimate holds at 1
  const Simulation sim(load_scene_file(kReference, {"numerics.damping=centred"}));
  const double at_estimate = sim.model().dt_critical;
  EXPECT_MENTIONS(error_of({"numerics.damping=centred", "numerics.dt=" + std::to_string(0.99 * at_estimate)}), "numerics.dt",
                  "centred");
}

// A divergence names its likely cause, and blames dt only when dt was near the estimate.
TEST(SceneErrors, DivergenceNamesItsLikelyCause) {
  auto message = [](const std::vector<std::string>& overrides) {
    Simulation sim(load_scene_file(kReference, overrides));
    for (int i = 0; i < 2000 && sim.step() == StepStatus::kOk; ++i) {
    }
    EXPECT_EQ(sim.state().status, StepStatus::kDiverged);
    return sim.status_message();
  };
  // Static displacements are millimetres: a limit of 1e-9 m, below them, is refused before the
  // pass; one of twice the static state's reach stops a sound run within steps.
  EXPECT_MENTIONS(error_of({"numerics.divergence_limit=1e-9"}), "'numerics.divergence_limit' = 1e-09 m",
                  "static state already reaches", " at x = ");
  const double reach = Simulation(load_scene_file(kReference)).state().u.cwiseAbs().maxCoeff();
  const std::string limit = message({"numerics.divergence_limit=" + std::to_string(2.0 * reach)});
  EXPECT_MENTIONS(limit, "numerics.divergence_limit", "within the line's own displacements");
  EXPECT_EQ(limit.find("numerics.dt"), std::string::npos) << limit;
  EXPECT_EQ(limit.find("stability estimate"), std::string::npos) << limit;
  // The contact wire rises by centimetres under the reference pantograph (validation.md section 2:
  // 48-65 mm at the supports): a 3 cm limit is reached by the pass's own motion, a little at a
  // step, and the message says so rather than blaming dt.
  const std::string lowered = message({"numerics.divergence_limit=0.03"});
  EXPECT_MENTIONS(lowered, "numerics.divergence_limit", "0.03", "below its default");
  EXPECT_EQ(lowered.find("stability estimate"), std::string::npos) << lowered;
  // 0.001 N/m under some 100 N: the strips would sink 1e5 m into the wire.
  const std::string soft = message({"contact.stiffness=0.001"});
  EXPECT_MENTIONS(soft, "contact.stiffness");
  EXPECT_EQ(soft.find("stability estimate"), std::string::npos) << soft;
}

// A design the statics cannot build names the field of the line's kind that makes it so: a
// compound line's hangers and auxiliary, a stitched line's stitch wire.
TEST(SceneErrors, DesignStaticsRefusalsNameTheKindsFields) {
  const std::string compound = test_scenes::scene_path("compound_catenary.yaml");
  EXPECT_MENTIONS(test_scenes::refusal_of(compound, {"hangers.positions=[5.0]"}), "hangers.positions", "auxiliary messenger",
                  "push");
  EXPECT_MENTIONS(test_scenes::refusal_of(compound, {"auxiliary_messenger.height=1.49"}), "lower auxiliary_messenger.height");
  const std::string stitched = test_scenes::scene_path("reference_55m_stitched.yaml");
  EXPECT_MENTIONS(test_scenes::refusal_of(stitched, {"stitch_wire.tension=1"}), "stitch_wire.tension 1 N", "raise it");
  EXPECT_MENTIONS(test_scenes::refusal_of(stitched, {"stitch_wire.tension=1e5"}), "lower stitch_wire.tension");
  // A dropper of 5 mm is refused as too short for its fittings (not as hanging below), and a
  // drawn dropper error too long for a hanger names the spread that drew it and the hanger (not a
  // list of errors the scene does not give).
  EXPECT_MENTIONS(test_scenes::refusal_of(compound, {"auxiliary_messenger.height=1.3"}), "'line.encumbrance'", "hangs only",
                  "shorter than 0.01 m");
  EXPECT_MENTIONS(test_scenes::refusal_of(compound, {"imperfections.dropper_length_std=0.05"}),
                  "'imperfections.dropper_length_std' = 0.05", "the hanger at");
  // A one-section line's per-span list is its top-level field's, not under line.
  EXPECT_MENTIONS(test_scenes::refusal_of(compound, {"hangers.positions=null", "hangers.positions_per_span=[[2.5],[2.5]]"}),
                  "'hangers.positions_per_span'");
  // Found in building, named with the file as a refusal found in reading is.
  const std::string named = stitched + ": droppers: at x = ";
  EXPECT_MENTIONS(test_scenes::refusal_of(stitched, {"stitch_wire.tension=1"}), named.c_str());
}

// A field of a line of several sections is named by its section where the section gives it, in
// reading and in the checks across a section's fields alike.
TEST(SceneErrors, ASectionsFieldIsNamedByItsSection) {
  const std::string mixed = test_scenes::scene_path("catenary_to_trolley_wire.yaml");
  EXPECT_MENTIONS(test_scenes::refusal_of(mixed, {"sections[1].contact_wire_count=2"}), "'sections[1].contact_wire_count' = 2",
                  "add droppers");
  EXPECT_MENTIONS(test_scenes::refusal_of(mixed, {"sections[1].messenger_supports={stiffness: 1e5}"}),
                  "'sections[1].messenger_supports' = (given)");
}

// Values the design cannot start from, refused by the field that makes them so: no weight to
// hang droppers by, no force for eq. 6's overlap rise, an endless pass that ends where it starts.
// A refusal found in a section's own statics names the file once.
TEST(SceneErrors, ADesignWithoutWeightForceOrTravelIsRefusedByItsField) {
  using test_scenes::refusal_of;
  using test_scenes::scene_path;
  EXPECT_MENTIONS(refusal_of(scene_path("reference_55m.yaml"), {"gravity=0"}), "'gravity' = 0", "droppers");
  const std::string two = scene_path("reference_55m_two_sections.yaml");
  EXPECT_MENTIONS(refusal_of(two, {"pantographs[0].static_uplift=0"}), "'overlap.design_force' = (missing)", "overlap.support_rise");
  const std::string deep = refusal_of(two, {"contact_wire.presag=0.5"});
  EXPECT_EQ(deep.find(two + ": "), 0u) << deep;
  EXPECT_EQ(deep.find(two, 1), std::string::npos) << deep;
  EXPECT_MENTIONS(refusal_of(scene_path("reference_55m_endless.yaml"), {"train.end=0"}), "'train.end' = 0", "beyond 0 m");
}

// A hinged arm is known by any of its own fields: one without its length is refused for the
// length, not for a spring's stiffness.
TEST(SceneErrors, AHingedArmWithoutItsLengthIsRefusedForTheLength) {
  const std::string hinged = test_scenes::scene_path("reference_55m_hinged_arms.yaml");
  EXPECT_MENTIONS(test_scenes::refusal_of(hinged, {"steady_arms.length=null"}), "'steady_arms.length' = (missing)");
  EXPECT_MENTIONS(test_scenes::refusal_of(hinged, {"steady_arms.length=null", "steady_arms.stiffness=1e4"}),
                  "'steady_arms.stiffness' = (given with linear_mass)");
}

// Two stations of a wire (supports, droppers, hangers, the clamps of stitch wires and bridles)
// closer than a dropper's or a clamp's fitting, 1 cm, are refused by the field that put the one
// beside the support or the other station there. A stitch wire or bridle of 10 um would put 5 um
// elements in the mesh (a contact patch sized for them overflows the statics' reservation), and a
// hanger 1 mm from its support is no fault of the auxiliary's tension. At 2 cm (clamps 1 cm from
// the support) the line is built; at the same station the two are one node.
TEST(SceneErrors, StationsCloserThanAFittingAreRefusedByTheirField) {
  using test_scenes::refusal_of;
  using test_scenes::scene_path;
  struct Case {
    const char* file;
    std::vector<std::string> o;
    const char* field;
  };
  const std::vector<Case> refused = {
      {"reference_55m_stitched.yaml", {"stitch_wire.length=1e-5"}, "'stitch_wire.length' = 1e-05"},
      {"reference_55m_stitched.yaml", {"stitch_wire.length=null", "stitch_wire.lengths=[16,16,1e-5,16,16,16,16,16,16]"},
       "'stitch_wire.lengths' = 1e-05"},
      {"trolley_wire_bridle.yaml", {"bridle.length=1e-5", "bridle.tension=1e5"}, "'bridle.length' = 1e-05"},
      {"compound_catenary.yaml", {"hangers.positions=[0.001,7.5,12.5,17.5,22.5,27.5,32.5,37.5,42.5,47.5]"},
       "'hangers.positions' = 0.001"},
      {"compound_catenary.yaml", {"hangers.positions=[2.5,4.995,12.5,17.5,22.5,27.5,32.5,37.5,42.5,47.5]"},
       "hangers.positions"},  // (beside a dropper: either may be named, with the other)
  };
  for (const Case& c : refused) {
    SCOPED_TRACE(std::string(c.file) + " " + c.o.back());
    const std::string message = refusal_of(scene_path(c.file), c.o);
    EXPECT_NE(message.find(c.field), std::string::npos) << message;
    EXPECT_NE(message.find("at least 0.01 m apart"), std::string::npos) << message;
  }
  EXPECT_EQ(refusal_of(scene_path("reference_55m_stitched.yaml"), {"stitch_wire.length=0.02"}), "");
  EXPECT_EQ(refusal_of(scene_path("compound_catenary.yaml"), {"hangers.positions=[2.5,5.0,12.5,17.5,22.5,27.5,32.5,37.5,42.5,47.5]"}),
            "");  // (a hanger at a dropper's station: one node)
}

// A limit computed from the scene is printed rounded toward what it allows, so that the number a
// refusal gives is accepted when given back: on the reference hinged-arm line the least pull-off
// is 233.85102 N (to nearest, 233.851: refused again), on the reference rail the least profile EI
// 46431.4453 N m^2 (to ten digits, 46431.44531: refused again).
TEST(SceneErrors, TheLimitARefusalPrintsIsItselfAllowed) {
  using test_scenes::refusal_of;
  using test_scenes::scene_path;
  struct Case {
    const char* file;
    const char* key;
    const char* too_low;
  };
  for (const Case& c : {Case{"reference_55m_hinged_arms.yaml", "steady_arms.pull_off", "100"},
                        Case{"rigid_conductor_rail.yaml", "conductor_rail.bending_stiffness", "1000"}}) {
    SCOPED_TRACE(c.key);
    const std::string message = refusal_of(scene_path(c.file), {std::string(c.key) + "=" + c.too_low});
    const std::size_t at = message.find("at least ");
    ASSERT_NE(at, std::string::npos) << message;
    const std::string least = message.substr(at + 9, message.find(' ', at + 9) - (at + 9));
    EXPECT_EQ(refusal_of(scene_path(c.file), {std::string(c.key) + "=" + least}), "") << "printed: " << least;
  }
}

// A required key that is missing while a key within two letters of it is given names that key:
// the map's unknown keys are otherwise reported only after the refusal, never.
TEST(SceneErrors, AMissingKeyNamesTheMisspeltOneGiven) {
  EXPECT_MENTIONS(error_of({"contact_wire.tension=null", "contact_wire.tenson=20000"}), "'contact_wire.tension' = (missing)",
                  "'tenson', misspelt?");
  EXPECT_MENTIONS(test_scenes::refusal_of(test_scenes::scene_path("rigid_conductor_rail.yaml"),
                                          {"conductor_rail.support_stiffness=null", "conductor_rail.support_stifness=1e7"}),
                  "'conductor_rail.support_stiffness' = (missing)", "'support_stifness', misspelt?");
  // Nothing near: the refusal as it was.
  EXPECT_EQ(error_of({"contact_wire.tension=null"}).find("misspelt"), std::string::npos);
}

// A negative speed is refused with the range the line allows (0 up to below the wave speed), not
// the reader's [0, inf); the filters' cutoffs with their least, 0.1 Hz; a rail section of one span
// by the field that gave its spans.
TEST(SceneErrors, SpeedFiltersAndARailSectionsSpansAreRefusedByWhatAllowsThem) {
  EXPECT_MENTIONS(error_of({"train.speed_kmh=-100"}), "'train.speed_kmh' = -100", "wave speed");
  EXPECT_MENTIONS(error_of({"output.filter_cutoff=1e-300"}), "'output.filter_cutoff' = 1e-300", "[0.1, 10000]");
  EXPECT_MENTIONS(error_of({"output.sensor_bandwidth=0.05"}), "'output.sensor_bandwidth' = 0.05", "[0.1, 10000]");
  EXPECT_EQ(error_of({"output.filter_cutoff=0.1", "output.sensor_bandwidth=0.1"}), "");
  EXPECT_MENTIONS(test_scenes::refusal_of(test_scenes::scene_path("rigid_conductor_rail.yaml"),
                                          {"sections=[{span_length: 10, span_count: 1}]", "overlap=null", "output.analysis_spans=null"}),
                  "'sections[0].span_count' = 1 span", "at least 2 spans");
}

// A binary file is refused as no text, by the line and column of its first byte that no UTF-8 text
// holds, before the YAML parser echoes its bytes into the message (which Python cannot decode) or
// reads past a NUL; a speed that is no number is refused with the range a speed has.
TEST(SceneErrors, BinaryFilesAndSpeedsThatAreNoNumbers) {
  const std::string nul = error_of_yaml(std::string("\0\xff\xfe", 3));
  EXPECT_MENTIONS(nul, "not text (a NUL byte at line 1, column 1)");
  const std::string high = error_of_yaml("line:\n  spans: [55]\n  \xff: 1\n");
  EXPECT_MENTIONS(high, "not UTF-8 text (byte 0xFF at line 3, column 3)");
  const std::string overlong = error_of_yaml("name: \xc0\xaf\n");  // '/' written in two bytes
  EXPECT_MENTIONS(overlong, "not UTF-8 text (byte 0xC0 at line 1, column 7)");
  const std::string set = error_of({"contact_wire.tension=\xff"});
  EXPECT_MENTIONS(set, "an override (--set): not UTF-8 text");
  for (const std::string& m : {nul, high, overlong, set}) EXPECT_EQ(m.find('\xff'), std::string::npos) << m;
  EXPECT_EQ(error_of_yaml("name: \"caten\xc3\xa4ry\"\n").find("UTF-8"), std::string::npos);  // (UTF-8 passes)
  EXPECT_MENTIONS(error_of({"train.speed_kmh=abc"}), "'train.speed_kmh' = 'abc'", "from 0 to below the contact wire's wave speed");
  EXPECT_MENTIONS(error_of({"train.speed_kmh=.nan"}), "'train.speed_kmh' = '.nan'", "at most 540");
}

// Nesting beyond the YAML reader's depth limit is said so (the reader's own message is "bad
// file"), and an override's long value is shown by its start and length, not echoed whole.
TEST(SceneErrors, DeepNestingAndLongOverridesAreSaidPlainly) {
  const std::string deep = std::string(10000, '[') + std::string(10000, ']');
  const std::string file = error_of_yaml("name: x\nline: " + deep + "\n");
  EXPECT_MENTIONS(file, "not valid YAML: nested", "levels deep", "the YAML reader's limit");
  EXPECT_EQ(file.find("bad file"), std::string::npos) << file;
  const std::string set = error_of({"line=" + deep});
  EXPECT_MENTIONS(set, "(20005 characters)", "levels deep");
  EXPECT_LT(set.size(), 600u) << set;
}
