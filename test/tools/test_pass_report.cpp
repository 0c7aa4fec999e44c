// simulate_pass --report on a short pass: every file of the pass and of the report is written, the
// HTML holds every section with its picture embedded, the limits are marked, and the report
// fails with a clear message on a directory without a pass. Runs the tools as child processes.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "../support/child_process.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim_test;

namespace {

const std::string kSimulatePass = test_scenes::program("simulate_pass");

class PassReport : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = temp_dir("catenary_sim_report_"); }
  void TearDown() override {
    if (!HasFailure()) std::system(("rm -rf '" + dir_ + "'").c_str());
  }
  std::string dir_;
};

// Six 55 m spans of the reference line at 250 km/h with 0.5 m elements: a pass of about two
// seconds that still has an analysis section (spans 2-3), droppers, steady arms and a spectrum.
// The limits are set so that some pass and one fails: 1 mm of uplift is far below any pass's.
TEST_F(PassReport, ShortPassBuildsEverySection) {
  const std::string out = dir_ + "/out";
  const ChildRun r = run_child({kSimulatePass, "--scene", test_scenes::kReference, "--out", out,
                          "--speed", "250", "--set", "line.span_count=6", "--set", "numerics.element_length=0.5",
                          "--set", "output.allowed_uplift=0.001", "--set", "output.max_stat_force=400", "--set",
                          "output.min_stat_force=0", "--set", "output.max_contact_loss_percent=0", "--set",
                          "output.dropper_series=true", "--report", "--no-progress"},
                         dir_ + "/log.txt", 300.0);
  ASSERT_FALSE(r.hung);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  for (const char* f : {"stats.json", "timeseries.csv", "force_processed.csv", "contact_losses.csv", "droppers.csv",
                        "dropper_rainflow.csv", "psd.csv", "dropper_series.csv", "report.html"})
    EXPECT_TRUE(exists(out + "/" + f)) << f;
  const std::vector<std::string> sections{"force", "head", "uplift", "histogram", "psd", "droppers", "losses"};
  for (const std::string& s : sections) {
    const std::string png = out + "/report_" + s + ".png";
    ASSERT_TRUE(exists(png)) << png;
    EXPECT_EQ(slurp(png).substr(1, 3), "PNG") << png;
  }
  const std::string page = slurp(out + "/report.html");
  EXPECT_NE(page.find("id='statistics'"), std::string::npos);
  for (const std::string& s : sections) EXPECT_NE(page.find("<h2 id='" + s + "'>"), std::string::npos) << s;
  // Self-contained: the pictures are in the page, nothing is linked.
  std::size_t images = 0;
  for (std::size_t at = page.find("src='data:image/png;base64,"); at != std::string::npos;
       at = page.find("src='data:image/png;base64,", at + 1))
    ++images;
  EXPECT_EQ(images, sections.size());
  EXPECT_EQ(page.find(".png'"), std::string::npos);
  // The limits: uplift fails (1 mm), the statistical maximum passes (400 N).
  const nlohmann::json j = nlohmann::json::parse(slurp(out + "/stats.json"));
  bool uplift_failed = false, max_passed = false;
  for (const auto& l : j.at("limits")) {
    if (l.at("name") == "max_uplift_m") uplift_failed = !l.at("pass").get<bool>();
    if (l.at("name") == "stat_max_force_N") max_passed = l.at("pass").get<bool>();
  }
  EXPECT_TRUE(uplift_failed);
  EXPECT_TRUE(max_passed);
  EXPECT_NE(page.find("FAIL"), std::string::npos);
  EXPECT_NE(page.find(">pass<"), std::string::npos);
  // The old keys are still there, the new ones beside them.
  const auto& p = j.at("pantographs").at(0);
  for (const char* k : {"mean_force_N", "contact_loss_percent", "max_uplift_at_support_m", "unfiltered",
                        "contact_loss_events", "spectrum", "measured"})
    EXPECT_TRUE(p.contains(k)) << k;
  EXPECT_FALSE(j.at("droppers").at("list").empty());
  EXPECT_EQ(j.at("steady_arms").size(), 3u);  // supports 2, 3, 4 bound the section [110, 220] m
}

// The 3-D line's section: its files written and drawn, the page one picture longer.
TEST_F(PassReport, ThreeDimensionalLineAddsTheLateralSection) {
  const std::string out = dir_ + "/out";
  const ChildRun r = run_child({kSimulatePass, "--scene", test_scenes::kReference, "--out", out,
                          "--speed", "250", "--set", "line.span_count=6", "--set", "numerics.element_length=0.5",
                          "--set", "stagger.contact_wire=[0.3,-0.3]", "--report", "--no-progress"},
                         dir_ + "/log.txt", 300.0);
  ASSERT_FALSE(r.hung);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  for (const char* f : {"lateral.csv", "lateral_histogram.csv", "blow_off.csv", "pull_off.csv", "dewirements.csv",
                        "report_lateral.png"})
    EXPECT_TRUE(exists(out + "/" + f)) << f;
  const std::string page = slurp(out + "/report.html");
  EXPECT_NE(page.find("<h2 id='lateral'>"), std::string::npos);
  std::size_t images = 0;
  for (std::size_t at = page.find("src='data:image/png;base64,"); at != std::string::npos;
       at = page.find("src='data:image/png;base64,", at + 1))
    ++images;
  EXPECT_EQ(images, 8u);  // the seven sections of a 2-D pass and the lateral one
  // Windless, with each messenger over its contact wire: the droppers hang plumb and the wires
  // move across the track by micrometres at most (blow_off.csv: under 1e-6 m), so the page says
  // so instead of drawing bars of nothing.
  EXPECT_NE(page.find("no blow-off"), std::string::npos);
  EXPECT_NE(page.find("coupled two-way through the droppers"), std::string::npos);
}

// In a wind the lateral page has its blow-off per span; on a rail nothing joins the planes and the
// page says that too.
TEST_F(PassReport, TheLateralPageSaysWhatMovesTheWiresAndWhatJoinsThePlanes) {
  // simulate_pass --report on `scene` with `extra` arguments into `name`; its page.
  auto page_of = [&](const std::string& scene, const std::string& name, std::vector<std::string> extra) {
    std::vector<std::string> args = {kSimulatePass, "--scene", scene, "--out", dir_ + "/" + name, "--report", "--no-progress"};
    args.insert(args.end(), extra.begin(), extra.end());
    const ChildRun r = run_child(args, dir_ + "/" + name + "_log.txt", 300.0);
    EXPECT_FALSE(r.hung);
    EXPECT_EQ(r.exit_code, 0) << r.out;
    return slurp(dir_ + "/" + name + "/report.html");
  };
  const std::string blown = page_of(test_scenes::kReference3d, "windy",
                                    {"--speed", "250", "--set", "line.span_count=6", "--set", "numerics.element_length=0.5"});
  EXPECT_NE(blown.find("and the blow-off per span"), std::string::npos);
  EXPECT_EQ(blown.find("no blow-off"), std::string::npos);
  EXPECT_NE(blown.find("<h2 id='droppers'>"), std::string::npos);
  const std::string rail = test_scenes::scene_path("rigid_conductor_rail_3d.yaml");
  const std::string still = page_of(rail, "rail", {});
  EXPECT_NE(still.find("no blow-off"), std::string::npos);
  EXPECT_NE(still.find("coupled to nothing"), std::string::npos);
  EXPECT_EQ(still.find("<h2 id='droppers'>"), std::string::npos);  // a rail has none to draw
  // Wind on the profile: blown off between its supports, still coupled to nothing.
  const std::string windy_rail = page_of(rail, "windy_rail", {"--set", "wind.speed=30"});
  EXPECT_NE(windy_rail.find("and the blow-off per span"), std::string::npos);
  EXPECT_NE(windy_rail.find("coupled to nothing"), std::string::npos);
}

// Hinged steady arms: the statistics table gives their k_A, pull-off and inclinations, as
// stats.json has them (k_A rounded to the newton per metre); a line of springs has no such row.
TEST_F(PassReport, HingedSteadyArmsAreListedWithTheirGeometry) {
  const std::string out = dir_ + "/out";
  const ChildRun r = run_child({kSimulatePass, "--scene", test_scenes::kReferenceHingedArms, "--out", out,
                          "--speed", "250", "--set", "line.span_count=6", "--set", "numerics.element_length=0.5",
                          "--report", "--no-progress"},
                         dir_ + "/log.txt", 300.0);
  ASSERT_FALSE(r.hung);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json stats = nlohmann::json::parse(slurp(out + "/stats.json"));
  ASSERT_FALSE(stats["steady_arms"].empty());
  const double k = stats["steady_arms"][0]["stiffness_N_per_m"].get<double>();
  std::ostringstream shown;
  shown.setf(std::ios::fixed);
  shown.precision(0);
  shown << k << " N/m";
  const std::string page = slurp(out + "/report.html");
  EXPECT_NE(page.find("hinged steady arms"), std::string::npos);
  EXPECT_NE(page.find(shown.str()), std::string::npos) << shown.str();
  const std::string plain = dir_ + "/plain";
  const ChildRun p = run_child({kSimulatePass, "--scene", test_scenes::kReference, "--out", plain, "--speed", "250",
                                "--set", "line.span_count=6", "--set", "numerics.element_length=0.5", "--report",
                                "--no-progress"},
                               dir_ + "/log_plain.txt", 300.0);
  ASSERT_EQ(p.exit_code, 0) << p.out;
  EXPECT_EQ(slurp(plain + "/report.html").find("hinged steady arms"), std::string::npos);
}

// A compound line: the table lists droppers and hangers on rows of their own, each with its count
// as stats.json marks them (30 droppers and 60 hangers over the six spans of the analysis section).
TEST_F(PassReport, CompoundLineListsHangersApartFromDroppers) {
  const std::string out = dir_ + "/out";
  const ChildRun r = run_child({kSimulatePass, "--scene", test_scenes::kCompound, "--out", out, "--report", "--no-progress"},
                               dir_ + "/log.txt", 300.0);
  ASSERT_FALSE(r.hung);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json stats = nlohmann::json::parse(slurp(out + "/stats.json"));
  int hangers = 0, droppers = 0;
  for (const auto& d : stats["droppers"]["list"]) (d.value("hanger", false) ? hangers : droppers) += 1;
  ASSERT_GT(hangers, 0);
  ASSERT_GT(droppers, 0);
  const std::string page = slurp(out + "/report.html");
  EXPECT_NE(page.find("(" + std::to_string(hangers) + " hangers)"), std::string::npos);
  EXPECT_NE(page.find("(" + std::to_string(droppers) + " droppers)"), std::string::npos);
  EXPECT_NE(slurp(out + "/droppers.csv").find(",hanger\n"), std::string::npos);
}

TEST_F(PassReport, ReportOfAnEmptyDirectoryFailsNamingTheFile) {
  const ChildRun r = run_child({"/usr/bin/python3", test_scenes::kSourceDir + "/scripts/pass_report", dir_},
                         dir_ + "/log.txt", 60.0);
  ASSERT_FALSE(r.hung);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("stats.json is missing"), std::string::npos) << r.out;
  EXPECT_FALSE(exists(dir_ + "/report.html"));
}

}  // namespace
