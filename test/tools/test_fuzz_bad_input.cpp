// Fuzz of bad input to the offline tools: generated bad scenes, --set overrides and
// command lines, each run as a child process of simulate_pass (and elasticity_curve). For each:
// a non-zero exit, no signal, no hang (10 s), no output file written (so nothing half-written and
// no NaN), and a message naming the field (or flag, or file) that is wrong.
//
// The inputs are generated from the reference scene itself: every numeric field it holds gets
// values no range allows (NaN, inf, 1e300, text, lists, maps), every map gets an unknown field
// and a scalar in its place, and the YAML text is corrupted in the ways a fuzzer finds.
// Deterministic (fixed seed): a failure is reproducible, never by chance.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "../support/child_process.hpp"
#include "../support/scene_refusal.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim_test;

namespace {

using test_scenes::kReference;
const std::string kSimulatePass = test_scenes::program("simulate_pass");
const std::string kElasticity = test_scenes::program("elasticity_curve");
const std::string kFrf = test_scenes::program("pantograph_frf");

// Runs argv to its end (at most `limit` s) with its output in dir/output.txt.
ChildRun run(const std::vector<std::string>& args, const std::string& dir, double limit = 10.0) {
  return run_child(args, dir + "/output.txt", limit);
}

// One bad input: the run must fail cleanly and name `field` (any of the alternatives).
struct Case {
  std::string what;                   // for the failure message
  std::vector<std::string> args;      // after the program
  std::vector<std::string> names;     // the message must contain one of these
};

void expect_rejected(const std::string& program, const Case& c, const std::string& dir, int* count) {
  const std::string out = dir + "/out";
  std::vector<std::string> args{program};
  for (const std::string& a : c.args) args.push_back(a == "@OUT" ? out : a);
  const ChildRun r = run(args, dir);
  ++*count;
  SCOPED_TRACE(c.what + "\n  message: " + r.out);
  EXPECT_FALSE(r.hung) << "hung (killed after 10 s)";
  EXPECT_EQ(r.signal, 0) << "killed by signal " << r.signal;
  EXPECT_NE(r.exit_code, 0) << "accepted";
  EXPECT_NE(r.exit_code, -1);
  bool named = false;
  for (const std::string& n : c.names) named = named || r.out.find(n) != std::string::npos;
  EXPECT_TRUE(named) << "the message names none of: " << ::testing::PrintToString(c.names);
  // Nothing written: a refused pass leaves no stats.json or CSV (so none half-written or NaN).
  EXPECT_FALSE(exists(out + "/stats.json")) << "stats.json written";
  EXPECT_FALSE(exists(out + "/timeseries.csv")) << "timeseries.csv written";
  if (exists(out)) std::system(("rm -rf '" + out + "'").c_str());
}

// The reference scene's fields as dotted --set keys and as the messages name them.
struct Field {
  std::string key;      // pantographs.0.masses.1
  std::string message;  // pantographs[0].masses[1]
  bool in_list = false;
};

void collect(const YAML::Node& n, const std::string& key, const std::string& msg, std::vector<Field>* numeric,
             std::vector<Field>* maps) {
  if (n.IsMap()) {
    if (!key.empty()) maps->push_back({key, msg});
    for (const auto& kv : n) {
      const std::string k = kv.first.Scalar();
      collect(kv.second, key.empty() ? k : key + "." + k, msg.empty() ? k : msg + "." + k, numeric, maps);
    }
  } else if (n.IsSequence()) {
    for (std::size_t i = 0; i < n.size(); ++i)
      collect(n[i], key + "." + std::to_string(i), msg + "[" + std::to_string(i) + "]", numeric, maps);
  } else if (n.IsScalar()) {
    double d = 0.0;
    if (YAML::convert<double>::decode(n, d)) numeric->push_back({key, msg, msg.back() == ']'});
  }
}

}  // namespace

TEST(FuzzBadInput, SetOverridesOfEveryField) {
  const std::string dir = temp_dir("catenary_sim_fuzz_");
  const YAML::Node root = YAML::LoadFile(kReference);
  std::vector<Field> numeric, maps;
  collect(root, "", "", &numeric, &maps);
  ASSERT_GT(numeric.size(), 30u);
  int count = 0;
  // No range of any numeric field allows these (the widest, train.start/end, are finite).
  const std::vector<std::string> bad_numbers = {".nan", ".inf", "-.inf", "1e300", "-1e300", "abc", "[1, 2]", "{a: 1}"};
  for (const Field& f : numeric)
    for (const std::string& v : bad_numbers) {
      // A list entry is named as list[i] by the scene, or by the list when its shape is wrong.
      std::vector<std::string> names{f.message};
      if (f.in_list) names.push_back(f.message.substr(0, f.message.rfind('[')));
      expect_rejected(kSimulatePass, {"--set " + f.key + "=" + v, {"--scene", kReference, "--out", "@OUT", "--set", f.key + "=" + v}, names},
                      dir, &count);
    }
  for (const Field& f : maps) {
    expect_rejected(kSimulatePass, {"unknown field in " + f.key, {"--scene", kReference, "--out", "@OUT", "--set", f.key + ".spam=1"},
                     {f.message + ".spam"}}, dir, &count);
    expect_rejected(kSimulatePass, {"scalar in place of " + f.key, {"--scene", kReference, "--out", "@OUT", "--set", f.key + "=5"},
                     {f.message}}, dir, &count);
  }
  RecordProperty("cases", count);
  std::system(("rm -rf '" + dir + "'").c_str());
}

// Every shipped scene's numeric fields, read in-process: values no range allows are refused
// naming the field (or its list), in whichever section or block of a newer kind it lies.
TEST(FuzzBadInput, EveryShippedScenesFieldsRefuseValuesNoRangeAllows) {
  const std::vector<std::string> scenes = {
      "calpe_example.yaml", "catenary_to_rigid_rail.yaml", "catenary_to_trolley_wire.yaml", "compound_catenary.yaml",
      "compound_catenary_3d.yaml", "reference_55m_3d.yaml", "reference_55m_3d_hinged_arms.yaml", "reference_55m_endless.yaml",
      "reference_55m_hinged_arms.yaml", "reference_55m_stitched.yaml", "reference_55m_stitched_3d.yaml",
      "reference_55m_two_heads.yaml", "reference_55m_two_pantographs.yaml", "reference_55m_two_sections.yaml",
      "rigid_conductor_rail.yaml", "rigid_conductor_rail_3d.yaml", "stitched_catenary_to_rigid_rail.yaml", "trolley_wire.yaml",
      "trolley_wire_bridle.yaml", "trolley_wire_bridle_3d.yaml"};
  int count = 0;
  for (const std::string& name : scenes) {
    const std::string path = test_scenes::scene_path(name);
    std::vector<Field> numeric, maps;
    collect(YAML::LoadFile(path), "", "", &numeric, &maps);
    for (const Field& f : numeric)
      for (const char* v : {".nan", "-.inf", "1e300", "abc"}) {
        const std::string message = test_scenes::refusal_of(path, {f.key + "=" + v});
        ++count;
        const bool named = message.find("'" + f.message + "'") != std::string::npos ||
                           (f.in_list && message.find("'" + f.message.substr(0, f.message.rfind('[')) + "'") != std::string::npos);
        EXPECT_TRUE(named) << name << " --set " << f.key << "=" << v << ": " << (message.empty() ? "accepted" : message);
      }
  }
  RecordProperty("cases", count);
}

TEST(FuzzBadInput, OverridePathsAndValues) {
  const std::string dir = temp_dir("catenary_sim_fuzz_");
  int count = 0;
  std::vector<Case> cases = {
      {"through a value", {"--set", "name.foo=1"}, {"name"}},
      {"through a number", {"--set", "contact_wire.tension.x=1"}, {"contact_wire.tension"}},
      {"huge index", {"--set", "pantographs.99999999999999999999999.static_uplift=1"}, {"index 99999999999999999999999"}},
      {"index past the end", {"--set", "pantographs.1.static_uplift=1"}, {"index 1"}},
      {"name as index", {"--set", "pantographs.lead.static_uplift=1"}, {"pantographs"}},
      {"empty key part", {"--set", "numerics..dt=1"}, {"numerics..dt"}},
      {"no '='", {"--set", "numerics.dt"}, {"numerics.dt"}},
      {"invalid YAML value", {"--set", "numerics.dt=[1,"}, {"numerics.dt"}},
      {"empty dropper list", {"--set", "droppers.positions=[]"}, {"droppers.positions"}},
      {"dropper outside the span", {"--set", "droppers.positions=[4.5, 60]"}, {"droppers.positions"}},
      {"filter above Nyquist", {"--set", "output.filter_cutoff=5000"}, {"output.filter_cutoff"}},
      {"pass ends before the analysis section", {"--set", "train.end=10"}, {"train.end"}},
      {"train starts off the line", {"--set", "train.start=-1"}, {"train.start"}},
      {"train starts beyond the line", {"--set", "train.start=1000"}, {"train.start"}},
      {"speed removed (0)", {"--set", "train.speed_kmh=null"}, {"train.speed_kmh"}},
      {"negative net uplift", {"--set", "pantographs.0.aero_coefficient=-1"}, {"pantographs[0].aero_coefficient"}},
      {"unknown preset", {"--set", "numerics.preset=ultra"}, {"numerics.preset"}},
      {"unknown pantograph type", {"--set", "pantographs.0.type=rigid"}, {"pantographs[0].type"}},
      {"two equal pantograph names",
       {"--set", "pantographs=[{name: a, type: moving_force, static_uplift: 100}, {name: a, type: moving_force, static_uplift: 100}]"},
       {"pantographs[1].name"}},
      {"dt above the stability limit", {"--set", "numerics.dt=0.01"}, {"numerics.dt"}},
      {"irregularity profile missing", {"--set", "imperfections.contact_wire_irregularity.csv=/nonexistent.csv"},
       {"imperfections.contact_wire_irregularity.csv", "/nonexistent.csv"}},
      {"irregularity profile is a directory", {"--set", "imperfections.contact_wire_irregularity.csv=/tmp"},
       {"imperfections.contact_wire_irregularity.csv", "directory"}},
      {"irregularity profile is /dev/zero", {"--set", "imperfections.contact_wire_irregularity.csv=/dev/zero"},
       {"imperfections.contact_wire_irregularity.csv"}},
      {"irregularity shorter than the mesh", {"--set", "imperfections.contact_wire_irregularity={rms: 0.001, wavelength_min: 0.1, wavelength_max: 50}"},
       {"imperfections.contact_wire_irregularity.wavelength_min"}},
      {"wear beyond half the section", {"--set", "imperfections.contact_wire_wear.section_loss=0.9"}, {"imperfections.contact_wire_wear.section_loss"}},
      {"more memory than the machine", {"--set", "line.span_count=10000", "--set", "line.span_length=500", "--set", "numerics.element_length=0.01"},
       {"memory", "GiB"}},
      {"a pass that never ends (speed)", {"--speed", "1e-300"}, {"--max-steps"}},
      {"a pass of billions of steps (0.001 km/h)", {"--speed", "0.001"}, {"--max-steps"}},
      {"pantograph masses of 1e-12 kg", {"--set", "pantographs.0.masses=[1e-12, 1e-12, 1e-12]"}, {"--max-steps", "masses"}},
      {"speed out of range", {"--speed", "600"}, {"--speed"}},
      {"speed not a number", {"--speed", "fast"}, {"--speed"}},
      {"bag rate NaN", {"--bag-rate", "nan"}, {"--bag-rate"}},
      {"unknown flag", {"--sped", "300"}, {"--sped"}},
      {"--set without a value", {"--set"}, {"--set"}},
  };
  for (Case c : cases) {
    std::vector<std::string> args{"--scene", kReference, "--out", "@OUT"};
    args.insert(args.end(), c.args.begin(), c.args.end());
    c.args = args;
    expect_rejected(kSimulatePass, c, dir, &count);
  }
  // A stitch wire of 5 cm puts its clamps 2.5 cm from the support: elements a tenth of the
  // mesh's, dt 160 times shorter. The pass's refusal for its length names that element.
  expect_rejected(kSimulatePass, {"a stitch wire of 5 cm", {"--scene", test_scenes::scene_path("reference_55m_stitched.yaml"), "--out", "@OUT",
                                                            "--set", "stitch_wire.length=0.05", "--max-steps", "1e5"},
                                  {"shortest element is 0.025 m"}},
                  dir, &count);
  // An endless line's pass of 10 m is refused by --max-steps with its own length (the block
  // starts the train front 10 m before train.end, not at the line's station 0).
  expect_rejected(kSimulatePass, {"an endless line's 10 m pass", {"--scene", test_scenes::scene_path("reference_55m_endless.yaml"),
                                                                 "--out", "@OUT", "--set", "train.end=10", "--max-steps", "1"},
                                  {"(10 m at 300 km/h"}},
                  dir, &count);
  // Outputs that cannot be written, found before the pass.
  expect_rejected(kSimulatePass, {"--out is a file", {"--scene", kReference, "--out", kReference}, {kReference}}, dir, &count);
  expect_rejected(kSimulatePass, {"--out under /proc", {"--scene", kReference, "--out", "/proc/catenary_sim_out"}, {"/proc/catenary_sim_out"}},
                  dir, &count);
  expect_rejected(kSimulatePass, {"--bag into a missing directory", {"--scene", kReference, "--out", "@OUT", "--bag", "/nonexistent/x.bag"},
                   {"/nonexistent/x.bag"}}, dir, &count);
  // elasticity_curve shares the loader; its own flags are checked too.
  expect_rejected(kElasticity, {"elasticity: bad --set", {"--scene", kReference, "--set", "name.foo=1"}, {"name"}}, dir, &count);
  expect_rejected(kElasticity, {"elasticity: --step 0", {"--scene", kReference, "--step", "0"}, {"--step"}}, dir, &count);
  expect_rejected(kElasticity, {"elasticity: unknown flag", {"--scene", kReference, "--stepp", "1"}, {"--stepp"}}, dir, &count);
  // A 3-D line whose plan cannot be designed (a bridle too slack to turn the staggered wire
  // without arms steeper than 1 in 4 across the track) is refused as simulate_pass refuses it.
  expect_rejected(kElasticity, {"elasticity: a 3-D line's plan", {"--scene", test_scenes::scene_path("trolley_wire_bridle_3d.yaml"),
                                                                   "--set", "bridle.tension=900"}, {"bridle.tension"}},
                  dir, &count);
  // The lower bound as written (5), not std::to_string's 5.000000.
  expect_rejected(kFrf, {"frf: --fmax below --fmin", {kReference, "--pantograph", "pantograph", "--out", "@OUT", "--fmin",
                                                       "5", "--fmax", "1"}, {"--fmax: must be >= --fmin (5)"}},
                  dir, &count);
  RecordProperty("cases", count);
  std::system(("rm -rf '" + dir + "'").c_str());
}

TEST(FuzzBadInput, CorruptedSceneFiles) {
  const std::string dir = temp_dir("catenary_sim_fuzz_");
  const std::string text = slurp(kReference);
  std::mt19937 rng(20261123);  // fixed: the same files every run
  int count = 0;
  auto scene_case = [&](const std::string& what, const std::string& body, std::vector<std::string> names) {
    const std::string path = dir + "/scene.yaml";
    std::ofstream(path) << body;
    names.push_back(path);  // failures to parse at all name the file
    expect_rejected(kSimulatePass, {what, {"--scene", path, "--out", "@OUT"}, names}, dir, &count);
  };
  scene_case("non-scalar key", text + "? [a, b]\n: 1\n", {"key"});
  scene_case("map key", text + "? {a: 1}\n: 1\n", {"key"});
  scene_case("duplicate top-level key", "name: other\n" + text, {"name"});
  {
    std::string t = text;
    t.replace(t.find("train:\n"), 7, "train:\n  speed_kmh: 250.0\n");
    scene_case("duplicate nested key", t, {"train.speed_kmh"});
  }
  scene_case("empty value", text.substr(0, text.find("train:")) + "train:\n  speed_kmh:\n" +
                                text.substr(text.find("numerics:")), {"train.speed_kmh"});
  scene_case("unclosed list", text + "extra: [1, 2\n", {"not valid YAML"});
  scene_case("tab indentation", text + "train2:\n\tspeed: 1\n", {"not valid YAML", "train2"});
  scene_case("not a map", "- a\n- b\n", {"map"});
  scene_case("empty file", "", {"map"});
  // Random bytes overwrite a random stretch of the text: whatever it parses to, it must be
  // refused cleanly, or (a comment hit, a value changed within its range) run as a valid pass.
  for (int i = 0; i < 40; ++i) {
    std::string t = text;
    std::uniform_int_distribution<std::size_t> at(0, t.size() - 1);
    std::uniform_int_distribution<int> byte(0, 255), len(1, 4);
    const std::size_t p = at(rng);
    const int n = len(rng);
    for (int k = 0; k < n && p + k < t.size(); ++k) t[p + k] = static_cast<char>(byte(rng));
    const std::string path = dir + "/scene.yaml";
    std::ofstream(path) << t;
    const ChildRun r = run({kSimulatePass, "--scene", path, "--out", dir + "/out"}, dir);
    SCOPED_TRACE("random bytes at " + std::to_string(p) + ": " + r.out);
    EXPECT_FALSE(r.hung);
    EXPECT_EQ(r.signal, 0);
    if (r.exit_code == 0) {
      // The corruption hit a comment or changed a value within its range: a valid pass, whose
      // outputs must then be whole and finite.
      const std::string stats = slurp(dir + "/out/stats.json");
      EXPECT_EQ(stats.find("nan"), std::string::npos);
      EXPECT_NE(stats.find("\"pantographs\""), std::string::npos);
    } else {
      EXPECT_EQ(r.exit_code, 2);
      EXPECT_NE(r.out.find("scene"), std::string::npos) << "an error not about the scene";
    }
    std::system(("rm -rf '" + dir + "/out'").c_str());
    ++count;
  }
  // Files that are not scene files.
  expect_rejected(kSimulatePass, {"a directory", {"--scene", test_scenes::kSourceDir + "/config", "--out", "@OUT"}, {"directory"}}, dir, &count);
  expect_rejected(kSimulatePass, {"/dev/zero", {"--scene", "/dev/zero", "--out", "@OUT"}, {"/dev/zero", "MiB"}}, dir, &count);
  expect_rejected(kSimulatePass, {"missing file", {"--scene", dir + "/none.yaml", "--out", "@OUT"}, {"none.yaml"}}, dir, &count);
  RecordProperty("cases", count);
  std::system(("rm -rf '" + dir + "'").c_str());
}

// A pass the watchdog stops (exit 3) writes nothing: the output directories it made and its lock
// file are taken back, and a directory that was there keeps what it held and gains nothing.
// (A trolley wire at 10 N, its wave speed under 4 m/s, let below the train's speed: it diverges
// within a tenth of a second.)
TEST(FuzzBadInput, ADivergedPassLeavesNothingBehind) {
  const std::string dir = temp_dir("catenary_sim_diverged_");
  const std::vector<std::string> diverging{kSimulatePass, "--scene", test_scenes::kSourceDir + "/config/trolley_wire.yaml",
                                           "--set", "contact_wire.tension=10", "--set", "numerics.allow_supercritical=true",
                                           "--quiet", "--no-progress", "--out"};
  std::vector<std::string> fresh = diverging;
  fresh.push_back(dir + "/new/pass");
  const ChildRun a = run(fresh, dir, 60.0);
  EXPECT_EQ(a.exit_code, 3) << a.out;
  EXPECT_NE(a.out.find("diverged"), std::string::npos) << a.out;
  EXPECT_FALSE(exists(dir + "/new")) << "the output directories it made stayed";
  const std::string kept = dir + "/kept";
  ASSERT_EQ(::mkdir(kept.c_str(), 0755), 0);
  std::ofstream(kept + "/notes.txt") << "mine\n";
  std::vector<std::string> existing = diverging;
  existing.push_back(kept);
  const ChildRun b = run(existing, dir, 60.0);
  EXPECT_EQ(b.exit_code, 3) << b.out;
  EXPECT_EQ(slurp(kept + "/notes.txt"), "mine\n");
  EXPECT_FALSE(exists(kept + "/.catenary_sim.lock"));
  EXPECT_FALSE(exists(kept + "/stats.json"));
  std::system(("rm -rf '" + dir + "'").c_str());
}

TEST(FuzzBadInput, OutputTargetsThatAreNotRegularFiles) {
  // The tools' single-file outputs onto what is not a regular file (output_files.hpp): a FIFO is
  // written through (elasticity_curve) or refused before the pass (--bag: a rosbag seeks), never
  // renamed over; a link to a file stays a link. In a scratch directory: no system file touched.
  const std::string dir = temp_dir("catenary_sim_targets_");
  auto mode = [](const std::string& p) {
    struct stat st {};
    return ::lstat(p.c_str(), &st) == 0 ? st.st_mode : mode_t{0};
  };
  const std::string fifo = dir + "/pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // A reader on the FIFO (non-blocking open: no writer needed) that takes the curve afterwards.
  const int rd = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(rd, 0);
  const ChildRun e = run({kElasticity, "--scene", kReference, "--step", "5", "--out", fifo}, dir);
  EXPECT_EQ(e.exit_code, 0) << e.out;
  EXPECT_TRUE(S_ISFIFO(mode(fifo))) << "elasticity_curve replaced the FIFO";
  std::string got;
  char buf[4096];
  for (ssize_t n; (n = ::read(rd, buf, sizeof buf)) > 0;) got.append(buf, static_cast<std::size_t>(n));
  ::close(rd);
  EXPECT_EQ(got.rfind("x_m,", 0), 0u) << got.substr(0, 80);
  // No reader: refused at once, the FIFO kept.
  const ChildRun nr = run({kElasticity, "--scene", kReference, "--step", "5", "--out", fifo}, dir);
  EXPECT_NE(nr.exit_code, 0);
  EXPECT_FALSE(nr.hung);
  EXPECT_NE(nr.out.find("no reader"), std::string::npos) << nr.out;
  EXPECT_TRUE(S_ISFIFO(mode(fifo)));
  // --bag onto a FIFO: refused before the pass, naming the flag.
  const ChildRun b = run({kSimulatePass, "--scene", kReference, "--set", "numerics.preset=fast", "--out", dir + "/out",
                          "--bag", fifo, "--quiet"},
                         dir, 60.0);
  EXPECT_EQ(b.exit_code, 2) << b.out;
  EXPECT_NE(b.out.find("--bag"), std::string::npos) << b.out;
  EXPECT_TRUE(S_ISFIFO(mode(fifo)));
  // A link to a regular file: the link stays, the file gets the curve.
  const std::string file = dir + "/curve.csv", link = dir + "/link.csv";
  std::ofstream(file) << "old\n";
  ASSERT_EQ(::symlink("curve.csv", link.c_str()), 0);
  const ChildRun l = run({kElasticity, "--scene", kReference, "--step", "5", "--out", link}, dir);
  EXPECT_EQ(l.exit_code, 0) << l.out;
  EXPECT_TRUE(S_ISLNK(mode(link)));
  EXPECT_EQ(slurp(file).rfind("x_m,", 0), 0u);
  std::system(("rm -rf '" + dir + "'").c_str());
}

// The 3-D line's rooms, the pantograph heads and the YAML shapes (anchors, aliases, documents):
// each refused cleanly, naming the field (or what is refused), by every tool that reads a scene.
TEST(FuzzBadInput, ThreeDLineHeadsAndYamlShapes) {
  const std::string dir = temp_dir("catenary_sim_fuzz_");
  const std::string r3 = test_scenes::kReference3d;
  const std::string heads = test_scenes::kReferenceTwoHeads;
  int count = 0;
  struct SetCase {
    std::string scene, set;
    std::vector<std::string> names;
  };
  const std::vector<SetCase> sets = {
      // stagger
      {r3, "stagger.contact_wire=[]", {"stagger.contact_wire"}},
      {r3, "stagger.contact_wire=[0.7, -0.7]", {"stagger.contact_wire[0]"}},
      {r3, "stagger.messenger=[]", {"stagger.messenger"}},
      {r3, "stagger.per_support=true", {"stagger.contact_wire"}},
      {r3, "stagger.per_support=sometimes", {"stagger.per_support"}},
      {r3, "stagger.steady_arm_stiffness=-1", {"stagger.steady_arm_stiffness"}},
      {r3, "stagger.messenger=[.nan]", {"stagger.messenger[0]"}},
      // alignment
      {r3, "alignment.radius=50", {"alignment.radius"}},
      {r3, "alignment.curves=[{start: 0, length: 50, radius: 500, transition: 30}]", {"alignment.curves[0].transition"}},
      {r3, "alignment.curves=[{start: 1e6, length: 50, radius: 500}]", {"alignment.curves[0].start"}},
      {r3, "alignment.curves=5", {"alignment.curves"}},
      // wind and turbulence
      {r3, "wind.speed=90", {"wind.speed"}},
      {r3, "wind.direction=.nan", {"wind.direction"}},
      {r3, "wind.air_density=0", {"wind.air_density"}},
      {r3, "wind.contact_wire.diameter=1", {"wind.contact_wire.diameter"}},
      {r3, "wind.speed=0", {"wind.speed"}},
      {r3, "wind.turbulence.spacing=1e-9", {"wind.turbulence.spacing"}},
      {r3, "wind.turbulence.spacing=1e-6", {"wind.turbulence.spacing"}},
      {r3, "wind.turbulence.intensity=0", {"wind.turbulence.intensity"}},
      {r3, "wind.turbulence.max_frequency=1e9", {"wind.turbulence.max_frequency"}},
      {r3, "wind.turbulence.seed=-1", {"wind.turbulence.seed"}},
      {r3, "wind.blow_off_limit=0", {"wind.blow_off_limit"}},
      {r3, "wind.conductor_rail.height=0.11", {"wind.conductor_rail"}},  // a catenary has no profile
      {test_scenes::scene_path("rigid_conductor_rail_3d.yaml"), "wind={speed: 10, conductor_rail: {height: .nan}}", {"wind.conductor_rail.height"}},
      {test_scenes::scene_path("rigid_conductor_rail_3d.yaml"), "wind={speed: 10, messenger: {diameter: 0.01}}", {"wind.messenger"}},
      // the stitch wires' supports
      {test_scenes::scene_path("stitched_catenary_to_rigid_rail.yaml"), "sections[0].stitch_wire.at_supports=[5, 6]",
       {"sections[0].stitch_wire.at_supports"}},
      {test_scenes::kReferenceStitched, "stitch_wire.at_supports=[.nan]", {"stitch_wire.at_supports[0]"}},
      {test_scenes::kReferenceStitched, "stitch_wire.at_supports=[1e300]", {"stitch_wire.at_supports[0]"}},
      {test_scenes::kReferenceStitched, "stitch_wire.at_supports={1: 2}", {"stitch_wire.at_supports"}},
      // each support's own stitch-wire length
      {test_scenes::kReferenceStitched, "stitch_wire={lengths: [.nan], tension: 3500, linear_mass: 0.31}", {"stitch_wire.lengths[0]"}},
      {test_scenes::kReferenceStitched, "stitch_wire={lengths: [1e300], tension: 3500, linear_mass: 0.31}", {"stitch_wire.lengths[0]"}},
      {test_scenes::kReferenceStitched, "stitch_wire={lengths: {1: 2}, tension: 3500, linear_mass: 0.31}", {"stitch_wire.lengths"}},
      {test_scenes::kReferenceStitched, "stitch_wire.lengths=[18, 18]", {"stitch_wire.length"}},
      // the pantograph head across the track
      {r3, "pantograph_head.histogram_bin=1e-8", {"pantograph_head.histogram_bin"}},
      {r3, "pantograph_head.histogram_bin=1e-300", {"pantograph_head.histogram_bin"}},
      {r3, "pantograph_head.working_width=0", {"pantograph_head.working_width"}},
      {r3, "pantograph_head.on_dewirement=maybe", {"pantograph_head.on_dewirement"}},
      {r3, "pantograph_head.sway={times: [1, 0], lateral: [0, 0]}", {"pantograph_head.sway.times[1]"}},
      {r3, "pantograph_head.sway={amplitude: 0.1, times: [0]}", {"pantograph_head.sway"}},
      {r3, "numerics.gust_lead=5", {"numerics.gust_lead"}},
      {r3, "numerics.gust_lead_step=5", {"numerics.gust_lead_step"}},
      // heads
      {heads, "pantographs.0.heads.0.stiffness=0", {"pantographs[0].heads[0].stiffness"}},
      {heads, "pantographs.0.heads.0.collectors.0.offset=5", {"pantographs[0].heads[0].collectors[0].offset"}},
      {heads, "pantographs.0.heads=[]", {"pantographs[0].heads"}},
      {heads, "pantographs.0.heads.1.mass=.inf", {"pantographs[0].heads[1].mass"}},
      {heads, "pantographs.0.heads.0.collectors.0.working_width=1", {"pantographs[0].heads[0].collectors[0].working_width"}},
      {heads, "pantographs.0.heads.0.aero_coefficient=-1", {"pantographs[0].heads[0].aero_coefficient"}},
      // where a field cannot act, the speed limit, the offline external pantograph
      {kReference, "numerics.gust_lead=5", {"numerics.gust_lead"}},
      {kReference, "numerics.gust_lead_step=explicit", {"numerics.gust_lead_step"}},
      {kReference, "pantographs.0.collectors=[{offset: 0, working_width: 1}]", {"pantographs[0].collectors[0].working_width"}},
      {kReference, "train.speed_kmh=800", {"train.speed_kmh"}},
      {kReference, "train={speed: 130}", {"train.speed_kmh"}},
      {kReference, "pantographs=[{name: rig, type: external, static_uplift: 100}]", {"pantographs[0].type"}},
      // YAML shapes in an override's value
      {kReference, "name=&a [*a]", {"'*a'"}},
      {kReference, "numerics=&n {dt: *n}", {"'*n'"}},
  };
  for (const SetCase& c : sets)
    expect_rejected(kSimulatePass, {c.set, {"--scene", c.scene, "--out", "@OUT", "--set", c.set}, c.names}, dir, &count);
  expect_rejected(kSimulatePass, {"--speed above the wave speed", {"--scene", kReference, "--out", "@OUT", "--speed", "500"}, {"--speed"}},
                  dir, &count);
  // YAML shapes in a scene file, through every reader of scene files.
  const std::string text = slurp(kReference);
  const std::size_t name_at = text.find("\nname:") + 1, name_end = text.find('\n', name_at);
  auto with_name = [&](const std::string& line) { return text.substr(0, name_at) + line + text.substr(name_end); };
  std::string bomb = "name: bomb\na0: &a0 [1, 2, 3, 4, 5, 6, 7, 8, 9]";
  for (int i = 1; i < 10; ++i) {
    bomb += "\na" + std::to_string(i) + ": &a" + std::to_string(i) + " [";
    for (int k = 0; k < 9; ++k) bomb += (k ? ", *a" : "*a") + std::to_string(i - 1);
    bomb += "]";
  }
  struct FileCase {
    std::string what, body;
    std::vector<std::string> names;
  };
  const std::vector<FileCase> files = {
      {"anchor containing itself", with_name("name: &r [*r]"), {"'*r'"}},
      {"alias bomb", with_name(bomb), {"aliases expand"}},
      {"second document", text + "---\ntrain: {speed_kmh: 100}\n", {"second YAML document"}},
  };
  const std::string client = test_scenes::program("udp_rig_client"), hil = test_scenes::program("catenary_sim_hil_udp");
  for (const FileCase& f : files) {
    const std::string path = dir + "/scene.yaml";
    std::ofstream(path) << f.body;
    expect_rejected(kSimulatePass, {f.what, {"--scene", path, "--out", "@OUT"}, f.names}, dir, &count);
    expect_rejected(kElasticity, {"elasticity: " + f.what, {"--scene", path, "--out", "@OUT"}, f.names}, dir, &count);
    expect_rejected(hil, {"hil_udp: " + f.what, {"--scene", path, "--duration", "1", "--stats", "@OUT"}, f.names}, dir, &count);
    expect_rejected(client, {"udp_rig_client: " + f.what, {"--pantograph-scene", path}, f.names}, dir, &count);
  }
  RecordProperty("cases", count);
  std::system(("rm -rf '" + dir + "'").c_str());
}

// Inputs that once ran into trouble past the reader: a wire or pantograph mass of next to nothing
// (an overflowing stability estimate gives a NaN step or one far too long), a pass without a
// pantograph and a filter below what it can settle on (a pass that reports 0 N), a negative speed
// (to be refused with the line's range), a static state beyond the divergence limit (a pass that
// stops at its first step), a stiffness of next to nothing (a singular start). Each is refused as bad input, status 2, by what sets it.
TEST(FuzzBadInput, LightMassesNoPantographAndFiltersWithoutARecordAreRefused) {
  const std::string dir = temp_dir("catenary_sim_fuzz_");
  const std::string stitched = test_scenes::kReferenceStitched;
  struct SetCase {
    std::string scene;
    std::vector<std::string> sets;
    std::string names;
  };
  const std::vector<SetCase> cases = {
      {stitched, {"stitch_wire.linear_mass=1e-200"}, "the masses that set dt"},
      {stitched, {"stitch_wire.linear_mass=1e-300"}, "the masses that set dt"},
      {test_scenes::kCompound, {"auxiliary_messenger.linear_mass=1e-300"}, "the masses that set dt"},
      {kReference, {"pantographs[0].masses=[1e-300, 9.0, 6.0]"}, "the masses that set dt"},
      {stitched, {"pantographs=[]"}, "'pantographs' = (none)"},
      {stitched, {"output.filter_cutoff=1e-300"}, "'output.filter_cutoff' = 1e-300"},
      {stitched, {"output.sensor_bandwidth=1e-300"}, "'output.sensor_bandwidth' = 1e-300"},
      {test_scenes::kCompound, {"train.speed_kmh=-100"}, "wave speed"},
      // A contact spring of 1e-308 N/m (its range is open at 0) leaves the start's statics nothing
      // to hold the pantograph by: named among what to check.
      {kReference, {"contact.stiffness=1e-308"}, "contact.stiffness"},
      // A tonne at one point of a trolley wire on bridles: a static sag of 8.8 m, beyond the
      // watchdog's 5 m before the pass starts (it stopped the pass at its first step, status 3).
      {test_scenes::scene_path("trolley_wire_bridle.yaml"), {"imperfections={point_masses: [{station: 100, mass: 1000}]}"},
       "'numerics.divergence_limit' = 5 m: the line's static state already reaches"},
      {test_scenes::scene_path("trolley_wire_bridle.yaml"), {"numerics.divergence_limit=1e-300"},
       "'numerics.divergence_limit' = 1e-300 m"},
  };
  for (const SetCase& c : cases) {
    std::vector<std::string> args{kSimulatePass, "--scene", c.scene, "--out", dir + "/out", "--max-steps", "200000"};
    for (const std::string& s : c.sets) {
      args.push_back("--set");
      args.push_back(s);
    }
    const ChildRun r = run(args, dir, 60.0);
    SCOPED_TRACE(c.sets.front() + "\n  message: " + r.out);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.out.find(c.names), std::string::npos);
    EXPECT_FALSE(exists(dir + "/out/stats.json"));
    std::system(("rm -rf '" + dir + "/out'").c_str());
  }
}
