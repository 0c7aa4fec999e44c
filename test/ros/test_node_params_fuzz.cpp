// Fuzz of bad node parameters: catenary_sim_node, catenary_sim_hil_node and virtual_rig
// run as child processes against a master of this test's own, each with one private parameter
// set to a value its type or range does not allow (`_name:=value` on the command line, as a user
// would). For each: a non-zero exit, no signal, no hang (20 s), no output file written, and a
// message naming the parameter. Also: known cases by name (_publish_rate:=1e-10,
// _marker_rate:=1e-300, _at_end:=1, _line_frame:=5), unknown parameters warned about by name with
// the closest known one, unwritable output files refused at start-up, and a ~stats_file that
// becomes unwritable during the pass failing the node's exit code.
//
// The values are generated per parameter from its type (deterministic: a failure is reproducible).
// Every run gets a node name of its own: `_name:=value` stays on the master after the run.
#include <gtest/gtest.h>
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "../support/child_process.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim_test;

namespace {

const std::string kNode = test_scenes::program("catenary_sim_node");
const std::string kHilNode = test_scenes::program("catenary_sim_hil_node");
const std::string kRig = test_scenes::program("virtual_rig");
const std::string kHilUdpNode = test_scenes::program("catenary_sim_hil_udp_node");
const std::string& kScene = test_scenes::kReference;
const std::string& kHilScene = test_scenes::kReferenceHil;

bool port_open(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(port);
  const bool ok = connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  close(fd);
  return ok;
}

// A master of the test's own on a free loopback port, and a scratch directory.
class NodeParamsFuzz : public ::testing::Test {
 public:
  static void SetUpTestSuite() {
    dir_ = temp_dir("catenary_sim_params_");
    port_ = free_port();
    env_ = {"ROS_MASTER_URI=http://localhost:" + std::to_string(port_), "ROS_HOME=" + dir_,
            "ROS_LOG_DIR=" + dir_ + "/log", "ROSCONSOLE_FORMAT=[${severity}] ${message}",
            // (the tests below wait for a line of the node's: stdout to a file is else block-buffered)
            "ROSCONSOLE_STDOUT_LINE_BUFFERED=1"};
    master_ = new Child({"/usr/bin/rosmaster", "--core", "-p", std::to_string(port_)}, dir_ + "/master.log", env_);
    for (int i = 0; i < 400 && !port_open(port_); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  static void TearDownTestSuite() {
    if (master_ && master_->started()) kill(master_->pid(), SIGTERM);
    if (master_) master_->wait(10.0);
    delete master_;
    master_ = nullptr;
  }
  void SetUp() override { ASSERT_TRUE(port_open(port_)) << "rosmaster did not start; see " << dir_ << "/master.log"; }

  // Runs `program` as a node of a name of its own with the `_name:=value` arguments.
  ChildRun run(const std::string& program, const std::vector<std::string>& params, double limit = 20.0) {
    std::vector<std::string> args{program, "__name:=fuzz" + std::to_string(++runs_)};
    for (const std::string& p : params) args.push_back(p);
    Child c(args, dir_ + "/run.log", env_);
    return c.wait(limit);
  }

  // The node `name` runs a short pass (`source_scene` cut to six spans of 0.5 m elements, written
  // into `out`) at full speed with ~report_file `out`/pass_report.html, and exits at its end.
  ChildRun report_pass(const std::string& source_scene, const std::string& out, const std::string& name,
                       const std::string& html = "") {
    mkdir(out.c_str(), 0755);
    std::string text = slurp(source_scene);  // the node takes no --set
    const auto set = [&](const std::string& from, const std::string& to) {
      const std::size_t at = text.find(from);
      EXPECT_NE(at, std::string::npos) << from;
      if (at != std::string::npos) text.replace(at, from.size(), to);
    };
    set("span_count: 10", "span_count: 6");
    set("preset: accurate", "preset: accurate\n  element_length: 0.5");
    const std::string scene = out + "/short.yaml";
    std::ofstream(scene) << text;
    return Child({kNode, "__name:=" + name, "_scene:=" + scene, "_speed_kmh:=250", "_real_time_factor:=0",
                  "_at_end:=exit", "_publish_clock:=false",
                  "_report_file:=" + (html.empty() ? out + "/pass_report.html" : html)},
                 dir_ + "/" + name + ".log", env_)
        .wait(300.0);
  }

  static std::string dir_;
  static int port_;
  static std::vector<std::string> env_;
  static Child* master_;
  static int runs_;
};
std::string NodeParamsFuzz::dir_;
int NodeParamsFuzz::port_ = 0;
std::vector<std::string> NodeParamsFuzz::env_;
Child* NodeParamsFuzz::master_ = nullptr;
int NodeParamsFuzz::runs_ = 0;

enum class Kind { kNumber, kRate, kRigRate, kInteger, kBool, kString, kPath, kReportPath, kFrame, kAtEnd, kScene };

struct Param {
  std::string name;
  Kind kind;
};

// Values no parameter of the kind allows. Every one reaches the node with a type of its own:
// roscpp stores `_x:=5` as an integer, `_x:=1.5` (and nan, inf) as a double, true/false as a
// boolean, anything else as a string. The reading and the range checks are shared by all
// parameters, so each parameter gets one value of every class (wrong type, not finite, out of
// range), the class's values taken in turn over the parameters (`i`: the parameter's index);
// the rates get every tiny value (values that once crashed a node) and every parameter the empty string.
std::vector<std::string> bad_values(Kind k, std::size_t i) {
  auto pick = [i](const std::vector<std::string>& v) { return v[i % v.size()]; };
  const std::string wrong_type = pick({"abc", "true", "[1]", "{a: 1}"});
  const std::string not_finite = pick({"nan", "inf", "-inf"});
  const std::string out_of_range = pick({"-1", "1e300"});
  switch (k) {
    case Kind::kNumber: return {wrong_type, not_finite, out_of_range, ""};
    case Kind::kRate: return {wrong_type, not_finite, out_of_range, "", "0", "1e-10", "1e-300"};
    case Kind::kRigRate: return {wrong_type, not_finite, out_of_range, "", "1e-10", "1e-300"};  // (0: allowed)
    case Kind::kInteger: return {"1.5", "-1", "100", "abc", "true", "nan", ""};
    case Kind::kBool: return {"1", "0", "yes", "1.5", ""};
    case Kind::kString: return {"5", "1.5", "true"};
    case Kind::kPath: return {"5", "true", "/nonexistent_catenary_sim_dir/x.json", "/tmp"};
    // (a report's missing directory is created: one that cannot be)
    case Kind::kReportPath: return {"5", "true", "/proc/catenary_sim_dir/x.html", "/tmp"};
    case Kind::kFrame: return {"5", "true", "", "/line"};
    case Kind::kAtEnd: return {"1", "true", "", "rewind"};
    case Kind::kScene: return {"5", "", "/nonexistent_catenary_sim_dir/s.yaml"};
  }
  return {};
}

void expect_rejected(const ChildRun& r, const std::string& what, const std::string& name) {
  SCOPED_TRACE(what + "\n  output: " + r.out);
  EXPECT_FALSE(r.hung) << "hung (killed)";
  EXPECT_EQ(r.signal, 0) << "killed by signal " << r.signal;
  EXPECT_NE(r.exit_code, 0) << "accepted";
  EXPECT_NE(r.exit_code, -1);
  EXPECT_NE(r.out.find("~" + name), std::string::npos) << "the message does not name ~" << name;
}

// `base`: valid parameters (the scene) that the fuzzed one replaces. The runs go kParallel at a
// time (each waits on the master most of its time).
constexpr int kParallel = 4;
void fuzz(NodeParamsFuzz* t, const std::string& program, const std::vector<Param>& params,
          const std::vector<std::pair<std::string, std::string>>& base, const std::string& stats_dir, int* count) {
  struct Job {
    std::string what, name;
    std::vector<std::string> args;
  };
  std::vector<Job> jobs;
  for (std::size_t i = 0; i < params.size(); ++i) {
    const Param& p = params[i];
    for (const std::string& v : bad_values(p.kind, i)) {
      if (p.name == "speed_kmh" && v.empty()) continue;  // "" is "not given" (an empty launch argument)
      Job j{program + " _" + p.name + ":=" + v, p.name, {program, "__name:=fuzz" + std::to_string(++t->runs_)}};
      for (const auto& [n, bv] : base)
        if (n != p.name) j.args.push_back("_" + n + ":=" + bv);
      j.args.push_back("_" + p.name + ":=" + v);
      jobs.push_back(j);
    }
  }
  for (std::size_t first = 0; first < jobs.size(); first += kParallel) {
    std::vector<std::unique_ptr<Child>> children;
    for (std::size_t k = first; k < jobs.size() && k < first + kParallel; ++k)
      children.push_back(std::make_unique<Child>(jobs[k].args, t->dir_ + "/run" + std::to_string(k - first) + ".log", t->env_));
    for (std::size_t k = 0; k < children.size(); ++k) {
      const ChildRun r = children[k]->wait(20.0);
      expect_rejected(r, jobs[first + k].what, jobs[first + k].name);
      ++*count;
    }
  }
  // Refused at start-up: nothing written (so nothing half-written and no NaN in a file).
  for (const char* f : {"/stats.json", "/report.json"}) EXPECT_FALSE(exists(stats_dir + f)) << stats_dir << f;
}

}  // namespace

TEST_F(NodeParamsFuzz, NodeRejectsEveryBadValueNamingTheParameter) {
  const std::string out = dir_ + "/node";
  mkdir(out.c_str(), 0755);
  const std::vector<Param> params{
      {"scene", Kind::kScene},           {"speed_kmh", Kind::kNumber},       {"real_time_factor", Kind::kNumber},
      {"publish_rate", Kind::kRate},     {"shape_rate", Kind::kRate},        {"marker_rate", Kind::kRate},
      {"shape_resolution", Kind::kNumber}, {"vertical_scale", Kind::kRate}, {"lateral_scale", Kind::kRate},  {"line_frame", Kind::kFrame},
      {"at_end", Kind::kAtEnd},          {"stats_file", Kind::kPath},        {"publish_clock", Kind::kBool},
      {"paused", Kind::kBool},           {"wait_for_viewer", Kind::kNumber}, {"max_acceleration", Kind::kNumber},
      {"start_delay", Kind::kNumber},    {"wait_for_recorder", Kind::kNumber}, {"report_file", Kind::kReportPath}, {"view_pantograph", Kind::kString},
      {"strip_chart", Kind::kBool},      {"chart_window", Kind::kNumber}};
  int count = 0;
  fuzz(this, kNode, params, {{"scene", kScene}, {"stats_file", out + "/stats.json"}}, out, &count);
  EXPECT_GT(count, 60);
}

TEST_F(NodeParamsFuzz, HilNodeRejectsEveryBadValueNamingTheParameter) {
  const std::string out = dir_ + "/hil";
  mkdir(out.c_str(), 0755);
  const std::vector<Param> params{
      {"scene", Kind::kScene},           {"speed_kmh", Kind::kNumber},       {"hil/rate", Kind::kRate},
      {"hil/timeout", Kind::kNumber},    {"hil/extrapolate", Kind::kBool},   {"hil/hold_ramp", Kind::kNumber},
      {"hil/hold_deceleration", Kind::kNumber}, {"hil/report_file", Kind::kPath},
      {"hil/realtime_priority", Kind::kInteger}, {"hil/spin_wait", Kind::kNumber}, {"at_end", Kind::kAtEnd},
      {"stats_file", Kind::kPath},       {"line_frame", Kind::kFrame},       {"publish_rate", Kind::kRate},
      {"marker_rate", Kind::kRate},      {"start_delay", Kind::kNumber},     {"shape_rate", Kind::kRate},
      {"shape_resolution", Kind::kNumber}, {"wait_for_viewer", Kind::kNumber}, {"strip_chart", Kind::kBool},
      {"chart_window", Kind::kNumber}};
  int count = 0;
  fuzz(this, kHilNode, params,
       {{"scene", kHilScene}, {"stats_file", out + "/stats.json"}, {"hil/report_file", out + "/report.json"}}, out,
       &count);
  EXPECT_GT(count, 60);
}

TEST_F(NodeParamsFuzz, VirtualRigRejectsEveryBadValueNamingTheParameter) {
  const std::string out = dir_ + "/rig";
  mkdir(out.c_str(), 0755);
  const std::vector<Param> params{{"pantograph_scene", Kind::kScene}, {"rate", Kind::kRigRate},
                                  {"extrapolate", Kind::kBool}, {"report_file", Kind::kPath}};
  int count = 0;
  fuzz(this, kRig, params, {{"pantograph_scene", kScene}, {"report_file", out + "/report.json"}}, out, &count);
  EXPECT_GT(count, 15);
}

// Known cases, by name: the messages say the value as given and what is allowed.
TEST_F(NodeParamsFuzz, KnownCasesSayValueAndWhatIsAllowed) {
  struct Case {
    std::string arg, says;
  };
  for (const Case& c : {Case{"_publish_rate:=1e-10", "~publish_rate = 1e-10 rejected: allowed [1, 10000] Hz"},
                        Case{"_marker_rate:=1e-300", "~marker_rate = 1e-300 rejected: allowed [0.1, 1000] Hz"},
                        Case{"_at_end:=1", "~at_end = 1 (an integer) rejected: expected stop, loop or exit"},
                        Case{"_line_frame:=5", "~line_frame = 5 (an integer) rejected: expected a frame id"},
                        Case{"_stats_file:=/nonexistent_catenary_sim_dir/s.json",
                             "~stats_file = '/nonexistent_catenary_sim_dir/s.json' rejected: cannot write"}}) {
    const ChildRun r = run(kNode, {"_scene:=" + kScene, c.arg});
    SCOPED_TRACE(c.arg + "\n  output: " + r.out);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.out.find(c.says), std::string::npos);
  }
  // A speed within ~speed_kmh's range but beyond the scene's contact-wire wave speed (438 km/h on
  // reference_55m, 460 km/h on its HIL twin) is the parameter's fault, named as simulate_pass
  // names --speed.
  for (const auto& [node, scene] : {std::pair{kNode, kScene}, std::pair{kHilNode, kHilScene}}) {
    const ChildRun r = run(node, {"_scene:=" + scene, "_speed_kmh:=500"});
    SCOPED_TRACE(node + "\n  output: " + r.out);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.out.find("parameter ~speed_kmh = 500 km/h: allowed"), std::string::npos);
  }
}

// replay_markers says a bad value as it was written and its range in the same words as the
// other nodes (not "20000.000000 rejected: allowed [0.000000, ...]").
TEST_F(NodeParamsFuzz, ReplayMarkersSaysValueAndRangeAsWritten) {
  const ChildRun r = run(test_scenes::program("replay_markers"), {"_vertical_scale:=20000"});
  SCOPED_TRACE("output: " + r.out);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("~vertical_scale = 20000 rejected: allowed [1e-09, 10000]"), std::string::npos);
}

// Misspelt parameters are ignored with a warning naming them and the closest known name, for
// every node; the warning comes before any error (so a typo that leaves a required parameter
// unset is explained).
TEST_F(NodeParamsFuzz, UnknownParametersAreWarnedAboutByName) {
  ChildRun r = run(kNode, {"_vertical_scal:=5", "_real_time_facter:=0.5"});  // ~scene missing too
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("unknown parameter ~vertical_scal (ignored); did you mean ~vertical_scale?"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("unknown parameter ~real_time_facter (ignored); did you mean ~real_time_factor?"),
            std::string::npos) << r.out;
  EXPECT_NE(r.out.find("~scene is required"), std::string::npos) << r.out;
  r = run(kHilNode, {"_scene:=" + kHilScene, "_rate:=2000", "_hil/rate:=1"});
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("unknown parameter ~rate (ignored); did you mean ~hil/rate?"), std::string::npos) << r.out;
  r = run(kRig, {"_pantograph_scen:=x", "_rate:=-1"});
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("unknown parameter ~pantograph_scen (ignored); did you mean ~pantograph_scene?"),
            std::string::npos) << r.out;

  // Only a warning: a pass with a misspelt parameter runs (and its statistics hold no NaN).
  const std::string stats = dir_ + "/unknown_stats.json";
  r = run(kNode, {"_scene:=" + kScene, "_speed_kmh:=250", "_real_time_factor:=0", "_at_end:=exit",
                  "_publish_clock:=false", "_stats_file:=" + stats, "_vertical_scal:=5"},
          60.0);
  EXPECT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("unknown parameter ~vertical_scal (ignored)"), std::string::npos) << r.out;
  const std::string json = slurp(stats);
  EXPECT_NE(json.find("\"pantographs\""), std::string::npos) << json;
  nlohmann::json parsed;
  EXPECT_NO_THROW(parsed = nlohmann::json::parse(json)) << json;  // (a NaN or inf written would not parse)
}

// ~stats_file checked at start-up, but the directory removed during the pass: the end-of-pass
// write fails, the node says so and exits 1 (not 0), and nothing is left behind.
TEST_F(NodeParamsFuzz, StatsFileThatFailsAtTheEndFailsTheExitCode) {
  const std::string out = dir_ + "/vanishing";
  mkdir(out.c_str(), 0755);
  const std::string log = dir_ + "/vanishing.log";
  Child c({kNode, "__name:=vanishing", "_scene:=" + kScene, "_speed_kmh:=250", "_real_time_factor:=0",
           "_at_end:=exit", "_publish_clock:=false", "_start_delay:=3", "_stats_file:=" + out + "/stats.json"},
          log, env_);
  ASSERT_TRUE(c.started());
  // The start-up check has passed once the start delay is announced.
  bool announced = false;
  for (int i = 0; i < 600 && !announced; ++i) {
    announced = slurp(log).find("(~start_delay)") != std::string::npos;
    if (!announced) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_TRUE(announced) << slurp(log);
  ASSERT_EQ(rmdir(out.c_str()), 0) << std::strerror(errno);
  const ChildRun r = c.wait(60.0);
  EXPECT_FALSE(r.hung);
  EXPECT_EQ(r.signal, 0);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("~stats_file: cannot write '" + out + "/stats.json'"), std::string::npos) << r.out;
  EXPECT_FALSE(exists(out));
}

// A Step that reaches the end of the pass with at_end exit gets its answer (success false, stopped
// early at the end, the steps it took) before the node exits 0: the node shut down inside the
// service's callback, and the caller got a transport error instead.
TEST_F(NodeParamsFuzz, AStepToTheEndWithAtEndExitIsAnswered) {
  Child node({kNode, "__name:=stepping", "_scene:=" + kScene, "_speed_kmh:=250", "_real_time_factor:=0", "_paused:=true",
              "_at_end:=exit", "_publish_clock:=false"},
             dir_ + "/stepping.log", env_);
  // (reference_55m at 250 km/h: about 9100 steps, within one call's 100000)
  const ChildRun call = Child({"/usr/bin/rosservice", "call", "--wait", "/stepping/step", "steps: 100000"},
                              dir_ + "/stepping_call.log", env_)
                            .wait(120.0);
  EXPECT_EQ(call.exit_code, 0) << call.out;
  EXPECT_NE(call.out.find("success: False"), std::string::npos) << call.out;
  EXPECT_NE(call.out.find("stopped early"), std::string::npos) << call.out;
  const ChildRun r = node.wait(60.0);
  ASSERT_FALSE(r.hung) << r.out;
  EXPECT_EQ(r.exit_code, 0) << r.out;
}

// ~report_file: at the end of the pass the node writes the pass's files beside the page and draws
// the same report as simulate_pass --report (same sections, pictures embedded), then exits 0.
// A short pass (six spans, 0.5 m elements) at full speed; the page's checks are test_pass_report's.
TEST_F(NodeParamsFuzz, ReportFileIsWrittenAtTheEndOfThePass) {
  const std::string out = dir_ + "/report";
  const ChildRun r = report_pass(kScene, out, "reporting");
  const std::string html = out + "/pass_report.html";
  ASSERT_FALSE(r.hung) << r.out;
  EXPECT_EQ(r.signal, 0);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("pass report written to " + html), std::string::npos) << r.out;
  for (const char* f : {"stats.json", "timeseries.csv", "force_processed.csv", "contact_losses.csv", "droppers.csv",
                        "dropper_rainflow.csv", "psd.csv"})
    EXPECT_TRUE(exists(out + "/" + f)) << f;
  EXPECT_FALSE(exists(out + "/report.html"));  // the page is where ~report_file says
  const std::string page = slurp(html);
  const std::vector<std::string> sections{"force", "head", "uplift", "histogram", "psd", "droppers", "losses"};
  EXPECT_NE(page.find("id='statistics'"), std::string::npos);
  for (const std::string& s : sections) {
    EXPECT_NE(page.find("<h2 id='" + s + "'>"), std::string::npos) << s;
    EXPECT_EQ(slurp(out + "/report_" + s + ".png").substr(1, 3), "PNG") << s;
  }
  std::size_t images = 0;
  for (std::size_t at = page.find("src='data:image/png;base64,"); at != std::string::npos;
       at = page.find("src='data:image/png;base64,", at + 1))
    ++images;
  EXPECT_EQ(images, sections.size());
  // The statistics are the node's pass: the same keys as simulate_pass's, finite.
  const nlohmann::json j = nlohmann::json::parse(slurp(out + "/stats.json"));
  EXPECT_GT(j.at("pantographs").at(0).at("std_force_N").get<double>(), 0.0);
}

// On a 3-D line the node's report directory also holds the lateral files, as simulate_pass's does,
// and stats.json its "lateral" object (the contact point across the strip, blow-off per span).
TEST_F(NodeParamsFuzz, ReportFileOfA3dLineHasTheLateralFiles) {
  const std::string out = dir_ + "/report3d";
  const ChildRun r = report_pass(test_scenes::kReference3d, out, "reporting3d");
  ASSERT_FALSE(r.hung) << r.out;
  EXPECT_EQ(r.signal, 0);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  for (const char* f : {"stats.json", "timeseries.csv", "lateral.csv", "lateral_histogram.csv", "blow_off.csv",
                        "pull_off.csv", "dewirements.csv"})
    EXPECT_TRUE(exists(out + "/" + f)) << f;
  const nlohmann::json j = nlohmann::json::parse(slurp(out + "/stats.json"));
  ASSERT_TRUE(j.contains("lateral")) << j.dump();
  // Over the analysed spans: the contact point sweeps the +-0.3 m zigzag.
  const nlohmann::json& c = j.at("lateral").at("contact_points").at(0);
  EXPECT_GT(c.at("max_m").get<double>() - c.at("min_m").get<double>(), 0.4) << c.dump();
}

// A report into a directory that does not exist yet: created with its parents, as simulate_pass
// --out creates its directory, and the pass's files written into it.
TEST_F(NodeParamsFuzz, ReportFileIntoANewDirectoryCreatesIt) {
  const std::string out = dir_ + "/report_new", where = out + "/not/yet/there";
  const ChildRun r = report_pass(kScene, out, "reporting_new", where + "/pass_report.html");
  ASSERT_FALSE(r.hung) << r.out;
  EXPECT_EQ(r.signal, 0);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  for (const char* f : {"pass_report.html", "stats.json", "timeseries.csv"}) EXPECT_TRUE(exists(where + "/" + f)) << f;
}

// roslaunch runs nodes in ROS_HOME: a scene path relative to the package (scene:=config/...) is
// found in the package; one found nowhere is refused with that hint.
TEST_F(NodeParamsFuzz, RelativeSceneIsLookedForInThePackage) {
  const auto in_ros_home = [&](const std::string& args) {
    // (the shell keeps the last of duplicate variables, the inherited ones: env_ set again after it)
    std::string set;
    for (const std::string& e : env_) set += " '" + e + "'";
    return std::vector<std::string>{"/bin/sh", "-c", "cd '" + dir_ + "' && exec env" + set + " " + kNode + " " + args};
  };
  // Paused: it loads the scene and then holds until killed at the limit.
  const ChildRun found = Child(in_ros_home("__name:=relative_scene _scene:=config/reference_55m.yaml _paused:=true"),
                               dir_ + "/relative_scene.log", env_)
                             .wait(8.0);
  EXPECT_NE(found.out.find("scene reference_55m"), std::string::npos) << found.out;
  EXPECT_NE(found.out.find("using the package's"), std::string::npos) << found.out;
  const ChildRun missing =
      Child(in_ros_home("__name:=missing_scene _scene:=config/no_such_scene.yaml"), dir_ + "/missing_scene.log", env_)
          .wait(20.0);
  expect_rejected(missing, "a relative scene found nowhere", "scene");
  EXPECT_NE(missing.out.find("ROS_HOME"), std::string::npos) << missing.out;
}

// A report whose directory cannot take the pass's files is refused at start-up, naming ~report_file.
TEST_F(NodeParamsFuzz, ReportFileInAReadOnlyPlaceIsRefusedAtStartUp) {
  const ChildRun r = run(kNode, {"_scene:=" + kScene, "_report_file:=/proc/catenary_report.html"});
  expect_rejected(r, "~report_file in /proc", "report_file");
}

// The same for the HIL node's ~hil/report_file, written when the node is stopped (SIGINT).
TEST_F(NodeParamsFuzz, HilReportFileThatFailsAtExitFailsTheExitCode) {
  const std::string out = dir_ + "/vanishing_hil";
  mkdir(out.c_str(), 0755);
  const std::string log = dir_ + "/vanishing_hil.log";
  Child c({kHilNode, "__name:=vanishing_hil", "_scene:=" + kHilScene, "_hil/report_file:=" + out + "/report.json"},
          log, env_);
  ASSERT_TRUE(c.started());
  bool waiting = false;
  for (int i = 0; i < 600 && !waiting; ++i) {
    waiting = slurp(log).find("waiting for the first measurement") != std::string::npos;
    if (!waiting) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_TRUE(waiting) << slurp(log);
  ASSERT_EQ(rmdir(out.c_str()), 0) << std::strerror(errno);
  kill(c.pid(), SIGINT);
  const ChildRun r = c.wait(30.0);
  EXPECT_FALSE(r.hung);
  EXPECT_EQ(r.signal, 0);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("~hil/report_file: cannot write '" + out + "/report.json'"), std::string::npos) << r.out;
}

// catenary_sim_hil_udp_node names its own parameters in every error at start-up: the socket's
// (~hil/udp_bind), the rig's (~hil/udp_rig, ~hil/udp_allow), the scene's (~scene), never the
// command-line options of catenary_sim_hil_udp.
TEST_F(NodeParamsFuzz, HilUdpNodeErrorsNameItsOwnParameters) {
  auto expect_names = [](const ChildRun& r, const std::string& what, const std::string& name) {
    SCOPED_TRACE(what + "\n  output: " + r.out);
    EXPECT_FALSE(r.hung);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.out.find(name), std::string::npos) << "does not name " << name;
    EXPECT_EQ(r.out.find(" --"), std::string::npos) << "names a command-line option";
    EXPECT_EQ(r.out.find("~hil/udp_*"), std::string::npos);
  };
  expect_names(run(kHilUdpNode, {"_scene:=" + kHilScene, "_hil/udp_bind:=300.1.1.1"}), "bind", "~hil/udp_bind");
  expect_names(run(kHilUdpNode, {"_scene:=" + kHilScene, "_hil/udp_rig:=10.0.0.3:47801", "_hil/udp_allow:=10.0.0.2"}),
               "rig off the allow-list", "~hil/udp_allow");
  // A scene whose frames do not fit a packet: five external pantographs (a packet carries four).
  const std::string five = test_scenes::with_pantograph_copies(kHilScene, 5, dir_ + "/five_external.yaml");
  const ChildRun r = run(kHilUdpNode, {"_scene:=" + five});
  expect_names(r, "five external pantographs", "~scene = '" + five + "'");
  EXPECT_NE(r.out.find("at most 4"), std::string::npos) << r.out;
}

// virtual_rig refuses at start-up a ~pantograph_scene without a lumped pantograph it can step
// (over the topics it took it and died at the first contact point, the node waiting for ever),
// and over UDP names its parameters, not udp_rig_client's options.
TEST_F(NodeParamsFuzz, VirtualRigRefusesAPantographSceneWithoutLumpedPantographsAtStartUp) {
  for (const std::string transport : {"topics", "udp"}) {
    const ChildRun r = run(kRig, {"_pantograph_scene:=" + kHilScene, "_transport:=" + transport}, 10.0);
    SCOPED_TRACE(transport + "\n  output: " + r.out);
    EXPECT_FALSE(r.hung) << "accepted at start-up";
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.out.find("~pantograph_scene = '" + kHilScene + "': no lumped pantograph"), std::string::npos);
    EXPECT_EQ(r.out.find("--"), std::string::npos) << "names a command-line option";
  }
  const ChildRun r = run(kRig, {"_pantograph_scene:=" + kScene, "_transport:=udp", "_simulator:=abc:47800"}, 10.0);
  SCOPED_TRACE("output: " + r.out);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("~simulator"), std::string::npos);
  EXPECT_EQ(r.out.find("--"), std::string::npos) << "names a command-line option";
}

// virtual_rig over UDP writes ~report_file at exit as over the topics (here stopped by SIGINT
// before any simulator answered: no measurement sent).
TEST_F(NodeParamsFuzz, VirtualRigOverUdpWritesItsReportFile) {
  const std::string out = dir_ + "/rig_udp";
  mkdir(out.c_str(), 0755);
  const std::string report = out + "/report.json", log = dir_ + "/rig_udp.log";
  Child c({kRig, "__name:=rig_udp", "_pantograph_scene:=" + kScene, "_transport:=udp",
           "_simulator:=127.0.0.1:" + std::to_string(free_port()), "_report_file:=" + report},
          log, env_);
  ASSERT_TRUE(c.started());
  bool up = false;
  for (int i = 0; i < 600 && !up; ++i) {
    up = slurp(log).find("over UDP to") != std::string::npos;
    if (!up) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_TRUE(up) << slurp(log);
  kill(c.pid(), SIGINT);
  const ChildRun r = c.wait(30.0);
  EXPECT_FALSE(r.hung);
  EXPECT_EQ(r.exit_code, 0) << r.out;
  ASSERT_TRUE(exists(report)) << r.out;
  const nlohmann::json j = nlohmann::json::parse(slurp(report));
  EXPECT_EQ(j.at("measurements").get<int>(), 0);
  EXPECT_TRUE(j.contains("round_trip"));
}

// catenary_sim_hil_udp_node writes ~stats_file at the end of each pass and logs its statistics,
// as catenary_sim_hil_node does (with at_end loop the file is there while the node runs on).
TEST_F(NodeParamsFuzz, HilUdpNodeWritesTheStatisticsAtTheEndOfEachPass) {
  const std::string out = dir_ + "/udp_stats";
  mkdir(out.c_str(), 0755);
  const std::string stats = out + "/stats.json", log = dir_ + "/udp_stats.log";
  const std::string port = std::to_string(free_port());
  Child node({kHilUdpNode, "__name:=udp_stats", "_scene:=" + kHilScene, "_at_end:=loop", "_stats_file:=" + stats,
              "_hil/timeout:=1.0", "_hil/udp_bind:=127.0.0.1", "_hil/udp_port:=" + port},
             log, env_);
  Child rig({kRig, "__name:=udp_stats_rig", "_pantograph_scene:=" + kScene, "_transport:=udp",
             "_simulator:=127.0.0.1:" + port},
            dir_ + "/udp_stats_rig.log", env_);
  ASSERT_TRUE(node.started());
  ASSERT_TRUE(rig.started());
  // The reference pass is 6.6 s of simulation; 120 s of wall clock covers a loaded machine.
  bool written = false;
  for (int i = 0; i < 1200 && !written; ++i) {
    written = exists(stats);
    if (!written) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  const std::string text = slurp(log);
  kill(rig.pid(), SIGINT);
  kill(node.pid(), SIGINT);
  rig.wait(30.0);
  const ChildRun r = node.wait(30.0);
  ASSERT_TRUE(written) << "no ~stats_file while the node runs\n" << r.out;
  EXPECT_NE(text.find("catenary_sim_hil_udp: leading: mean"), std::string::npos) << text;
  const nlohmann::json j = nlohmann::json::parse(slurp(stats));
  EXPECT_TRUE(j.at("pantographs").at(0).at("mean_force_N").is_number()) << j.dump();
}
