// rostest companion of hil_viewer.test: catenary_sim_hil_node with ~wait_for_viewer holds the line
// while nobody watches (the rig's measurements notwithstanding), starts the pass once a viewer
// subscribes to `markers`, and draws the strip chart with a heads-up line naming the loop's mode.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>

#include <mutex>
#include <set>
#include <string>

#include "catenary_sim/ContactPointArray.h"
#include "catenary_sim/MeasuredContactForce.h"
#include "hil_rig.hpp"
#include "ros_test_support.hpp"

using namespace catenary_sim;

namespace {

using hil_rostest::point;
using hil_rostest::wait_for;

TEST(HilViewer, WaitsForTheViewerThenRunsWithTheStripChart) {
  ASSERT_TRUE(wait_for([] { return point().steps_per_period > 0; }, 30.0)) << "no hil/contact_point";
  const ContactPointArray first = point();
  // Nobody watches: 3 s of the rig's measurements do not start the pass (without the wait the
  // first one would, within a period).
  ros::WallDuration(3.0).sleep();
  const ContactPointArray held = point();
  EXPECT_EQ(held.mode, ContactPointArray::WAITING);
  EXPECT_EQ(held.step, first.step) << "stepped before a viewer subscribed";

  // A viewer subscribes: the pass starts (after the node's second for the viewer to draw).
  std::mutex mu;  // (the callbacks run on the spinner's threads)
  std::set<std::string> namespaces;
  std::string heading;
  auto seen = [&] {
    std::lock_guard<std::mutex> l(mu);
    return heading;
  };
  ros::Subscriber viewer = hil_rostest::heard_points->nh.subscribe<visualization_msgs::MarkerArray>(
      "markers", 2, [&](const visualization_msgs::MarkerArray::ConstPtr& msg) {
        std::lock_guard<std::mutex> l(mu);
        for (const auto& mk : msg->markers) {
          namespaces.insert(mk.ns);
          if (mk.ns == "chart_info" && mk.text.find("hardware in the loop") != std::string::npos) heading = mk.text;
        }
      });
  ASSERT_TRUE(wait_for([] { return point().mode == ContactPointArray::RUNNING; }, 20.0)) << int(point().mode);
  ASSERT_TRUE(wait_for([&] { return point().step > first.step + 500; }, 20.0)) << point().step;
  ASSERT_TRUE(wait_for([&] { return seen().find("running") != std::string::npos; }, 10.0)) << seen();
  std::lock_guard<std::mutex> l(mu);
  for (const char* ns : {"chart_axes", "chart_series", "chart_info"}) EXPECT_EQ(namespaces.count(ns), 1u) << ns;
  EXPECT_NE(heading.find("span"), std::string::npos) << heading;
}

}  // namespace

int main(int argc, char** argv) {
  ros_test::init(argc, argv, "test_hil_viewer");
  hil_rostest::HeardPoints h;
  hil_rostest::heard_points = &h;
  return hil_rostest::run_with_rig<MeasuredContactForce>("hil/contact_force", hil_rostest::measure_steady);
}
