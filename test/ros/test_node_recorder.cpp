// rostest companion of node_recorder.test: a recorder that subscribes late still gets the pass
// from its first step.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <std_msgs/String.h>

#include <string>

#include "catenary_sim/PantographStateArray.h"
#include "ros_test_support.hpp"

using namespace catenary_sim;
using ros_test::Recorder;
using ros_test::pass_status;
using ros_test::wait_for;


// rosbag on a loaded machine can take seconds to subscribe; a fixed start delay then loses the
// start of the pass. Here the "recorder" comes 4 s late: a pass at real_time_factor 0 would be
// far along (or over) by then, so the hold is what keeps the start.
TEST(NodeRecorder, ALateRecorderGetsThePassFromItsFirstStep) {
  ros::WallDuration(4.0).sleep();
  ASSERT_EQ(pass_status(), "waiting");
  Recorder<PantographStateArray> state("pantograph_state", 100000);  // the whole pass, none dropped
  ASSERT_TRUE(wait_for([&] { return pass_status() == "ended"; }, 150.0)) << "the pass did not start or end";
  const auto got = state.take();
  ASSERT_GT(got.size(), 2u);
  // Stamps are simulated time: the first state the recorder gets is the initial one (t = 0),
  // and the pass went on to the end of the line (at least one 55 m span at 300 km/h: 0.66 s).
  EXPECT_EQ(got.front().header.stamp.toSec(), 0.0);
  EXPECT_GT(got.back().header.stamp.toSec(), 0.66);
}

int main(int argc, char** argv) { return ros_test::ros_test_main(argc, argv, "test_catenary_sim_node_recorder"); }
