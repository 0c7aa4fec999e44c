// rostest companion of node_paused.test: a paused start, then the pass to its end (at_end stop).
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <std_srvs/SetBool.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/MarkerArray.h>

#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "catenary_sim/PantographStateArray.h"
#include "catenary_sim/Step.h"
#include "ros_test_support.hpp"

using namespace catenary_sim;
using ros_test::Recorder;
using ros_test::pass_status;
using ros_test::wait_for;


// rviz started with a paused pass (pass.launch rviz:=true paused:=true) subscribes to /tf after
// the node has sent its first transforms; tf is not latched, and the hold sends no new time. The
// viewer must still get the frames (else "No TF data" and every marker in Error), with the hold's
// stamp, and train_view, the frame of the strip chart.
TEST(NodePaused, AViewerConnectingDuringTheHoldGetsEveryFrameAtTheHoldsStamp) {
  ASSERT_EQ(pass_status(), "paused");
  ros::WallDuration(1.0).sleep();  // the node's first transforms are long gone
  Recorder<PantographStateArray> state("pantograph_state");
  ASSERT_TRUE(wait_for([&] { return state.size() > 0; }, 5.0));
  const ros::Time hold = state.take().back().header.stamp;
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  Recorder<visualization_msgs::MarkerArray> markers("markers");  // the markers send train_view
  ASSERT_TRUE(wait_for([&] { return markers.size() > 0; }, 5.0));
  bool chart = false;
  for (const auto& a : markers.take())
    for (const auto& mk : a.markers) chart = chart || (mk.ns.rfind("chart", 0) == 0 && mk.header.frame_id == "train_view");
  EXPECT_TRUE(chart) << "no strip chart in train_view";
  for (const char* frame : {"train", "pantograph_leading", "train_view"}) {
    std::string err;
    ASSERT_TRUE(buffer.canTransform("line", frame, ros::Time(0), ros::Duration(3.0), &err)) << frame << ": " << err;
    EXPECT_EQ(buffer.lookupTransform("line", frame, ros::Time(0)).header.stamp, hold) << frame;
  }
  EXPECT_EQ(state.take().back().header.stamp, hold) << "time moved while paused";
}

// After at_end stop the pass has ended: set_paused false and step say so, as pass_status does,
// and neither changes the state.
TEST(NodePaused, AfterTheEndTheAnswersAgreeWithPassStatus) {
  std_srvs::SetBool run;
  run.request.data = false;
  ASSERT_TRUE(ros::service::call("/catenary_sim/set_paused", run));
  ASSERT_TRUE(run.response.success) << run.response.message;
  // real_time_factor 0: the 6.6 s pass takes a few wall seconds.
  ASSERT_TRUE(wait_for([] { return pass_status() == "ended"; }, 120.0, 0.2)) << pass_status();
  Recorder<PantographStateArray> state("pantograph_state");
  ASSERT_TRUE(wait_for([&] { return state.size() > 0; }, 5.0));
  const PantographStateArray end = state.take().back();

  ASSERT_TRUE(ros::service::call("/catenary_sim/set_paused", run));
  EXPECT_FALSE(run.response.success);
  EXPECT_EQ(run.response.message, "the pass has ended; reset to run again");
  std_srvs::SetBool pause;
  pause.request.data = true;
  ASSERT_TRUE(ros::service::call("/catenary_sim/set_paused", pause));
  Step step;
  step.request.steps = 10;
  ASSERT_TRUE(ros::service::call("/catenary_sim/step", step));
  EXPECT_FALSE(step.response.success);
  EXPECT_EQ(step.response.message, "rejected: the pass has ended; reset to run again");
  EXPECT_EQ(step.response.steps_advanced, 0);
  EXPECT_EQ(step.response.total_steps, end.step);
  EXPECT_EQ(pass_status(), "ended");
}

// ~stats_file is the document simulate_pass writes as stats.json (docs/user_guide.md: "same fields
// as simulate_pass's stats.json"), with the line's statistics, not only the pantographs'.
TEST(NodePaused, StatsFileHasTheLinesStatistics) {
  std::string path;
  ASSERT_TRUE(ros::param::get("/catenary_sim/stats_file", path));
  std::ifstream in(path);
  ASSERT_TRUE(in.good()) << path;
  const nlohmann::json j = nlohmann::json::parse(in);
  for (const char* key : {"steady_arms", "droppers", "limits", "support_stations_m", "dropper_stations_m",
                          "allowed_uplift_m", "pantographs"})
    EXPECT_TRUE(j.contains(key)) << key;
  // config/reference_55m.yaml: 10 spans, so 11 supports, and 9 droppers in each span.
  ASSERT_TRUE(j.contains("support_stations_m"));
  EXPECT_EQ(j["support_stations_m"].size(), 11u);
  ASSERT_TRUE(j.contains("steady_arms"));
  EXPECT_FALSE(j["steady_arms"].empty());
  ASSERT_TRUE(j.contains("dropper_stations_m"));
  EXPECT_EQ(j["dropper_stations_m"].size(), 90u);
}

int main(int argc, char** argv) { return ros_test::ros_test_main(argc, argv, "test_catenary_sim_node_paused"); }
