// The contact force recorded in a bag by pass.launch (live node, record:=true) equals the
// offline runner's for the same scene and inputs: the same numbers, bit for bit, at every
// instant the node published. Both run the same core with the same fixed dt; only pacing differs.
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

#include "../support/child_process.hpp"
#include "catenary_sim/ContactForceArray.h"
#include "../support/scenes.hpp"

using catenary_sim_test::free_port;
using catenary_sim_test::temp_dir;

namespace {

std::map<double, catenary_sim::ContactForce> read_forces(const std::string& path) {
  std::map<double, catenary_sim::ContactForce> out;  // keyed by pantograph position
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  for (const rosbag::MessageInstance& mi : rosbag::View(bag, rosbag::TopicQuery("/contact_force"))) {
    const auto m = mi.instantiate<catenary_sim::ContactForceArray>();
    if (m && !m->pantographs.empty()) out[m->pantographs[0].position] = m->pantographs[0];
  }
  return out;
}

}  // namespace

TEST(BagEquality, LiveRecordingEqualsOfflineRunner) {
  const std::string dir = temp_dir("catenary_sim_bag_");
  const std::string scene = test_scenes::kReference;
  const std::string live = dir + "/live.bag", offline = dir + "/offline.bag";
  // A master of its own on a free loopback port. The node exits at the end of the pass, the
  // recorder closes the bag, and roslaunch ends with the node (required when headless).
  const int free = free_port();
  ASSERT_NE(free, 0) << "no free port on the loopback interface";
  const std::string port = std::to_string(free);
  const std::string env = "ROS_MASTER_URI=http://localhost:" + port + " ROS_HOME=" + dir;
  const std::string core = env + " timeout -k 5 300 roscore -p " + port + " > " + dir + "/roscore.log 2>&1 & echo $! > " +
                           dir + "/roscore.pid";
  const std::string launch = env + " timeout -k 10 180 roslaunch --wait catenary_sim pass.launch scene:=" + scene +
                             " speed_kmh:=250 real_time_factor:=0 at_end:=exit record:=true bag:=" + live + " > " +
                             dir + "/launch.log 2>&1";
  ASSERT_EQ(std::system(("bash -c '" + core + "'").c_str()), 0);
  const int rc = std::system(("bash -c '" + launch + "'").c_str());
  (void)!std::system(("bash -c 'kill $(cat " + dir + "/roscore.pid) 2>/dev/null; sleep 1'").c_str());
  ASSERT_EQ(rc, 0) << "roslaunch failed; see " << dir << "/launch.log";
  const std::string run = test_scenes::program("simulate_pass") + " --scene " + scene +
                          " --speed 250 --quiet --out " + dir + "/offline --bag " + offline + " --bag-rate 0";
  ASSERT_EQ(std::system(run.c_str()), 0);

  const auto recorded = read_forces(live), reference = read_forces(offline);
  // The node publishes at 200 Hz of wall time; a pass at about 30x real time gives tens of messages.
  ASSERT_GT(recorded.size(), 20u) << "too few /contact_force messages in " << live;
  ASSERT_GT(reference.size(), 5000u);
  std::size_t compared = 0;
  for (const auto& [x, f] : recorded) {
    const auto it = reference.find(x);
    ASSERT_NE(it, reference.end()) << "no offline step at pantograph position " << x;
    EXPECT_EQ(f.total, it->second.total) << "at x = " << x;
    EXPECT_EQ(f.collector_forces, it->second.collector_forces) << "at x = " << x;
    ++compared;
  }
  EXPECT_EQ(compared, recorded.size());
  // Positions span the line: the bag holds the whole pass, not only its start.
  EXPECT_GT(recorded.rbegin()->first, 500.0);
}
