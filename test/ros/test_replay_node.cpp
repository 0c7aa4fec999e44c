// rostest companion of replay.test: a pass written to a bag by simulate_pass --bag (the node's
// topics, no markers) is played back with rosbag play --clock; replay_markers must draw it: one
// marker array per recorded wire_shape, every part of the scene in it, the pantograph head at the
// recorded position of the same instant. plot_contact_force, started on the same playback, must
// write its PNG when the pass ends, and show the steady-arm uplift of stats.json (the pass's record
// at every step, carried by line_state), not a sample of the 10 Hz wire shape.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <std_msgs/String.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "catenary_sim/LineState.h"
#include "catenary_sim/PantographStateArray.h"
#include "catenary_sim/WireShapeArray.h"
#include "../support/child_process.hpp"
#include "ros_test_support.hpp"
#include "../support/scenes.hpp"

namespace {

bool wait_for(const std::function<bool()>& cond, double timeout_s) { return ros_test::wait_for(cond, timeout_s, 0.1); }

std::mutex mu;
std::vector<visualization_msgs::MarkerArray> received;

void on_markers(const visualization_msgs::MarkerArray::ConstPtr& m) {
  std::lock_guard<std::mutex> l(mu);
  received.push_back(*m);
}

std::string sh(const std::string& cmd) { return "bash -c '" + cmd + "'"; }

}  // namespace

TEST(Replay, RecordedPassIsDrawnAndPlotted) {
  const std::string dir = catenary_sim_test::temp_dir("catenary_sim_replay_");
  const std::string scene = test_scenes::kReference;
  const std::string bag = dir + "/pass.bag", png = dir + "/plot.png", csv = dir + "/uplift.csv";
  // The whole reference pass (550 m, 6.6 s at 300 km/h): state topics at 200 Hz, wire_shape at 10 Hz.
  ASSERT_EQ(std::system((test_scenes::program("simulate_pass") + " --scene " + scene + " --quiet --out " +
                         dir + "/offline --bag " + bag + " > " + dir + "/simulate_pass.log 2>&1").c_str()),
            0)
      << "see " << dir << "/simulate_pass.log";

  // What the bag holds: the pantograph position at every stamp, the stamps of the wire shapes.
  std::map<ros::Time, double> position;
  std::set<ros::Time> shape_stamps;
  std::map<long long, double> bag_uplift;  // steady arm station (mm) -> last recorded largest uplift (m)
  {
    rosbag::Bag b(bag, rosbag::bagmode::Read);
    for (const rosbag::MessageInstance& mi : rosbag::View(b)) {
      if (const auto s = mi.instantiate<catenary_sim::PantographStateArray>())
        position[s->header.stamp] = s->pantographs.at(0).position;
      if (const auto w = mi.instantiate<catenary_sim::WireShapeArray>()) shape_stamps.insert(w->header.stamp);
      if (const auto l = mi.instantiate<catenary_sim::LineState>())
        for (std::size_t k = 0; k < l->steady_arm_station.size(); ++k)
          bag_uplift[std::llround(1e3 * l->steady_arm_station[k])] = l->steady_arm_max_uplift[k];
    }
  }
  ASSERT_GT(shape_stamps.size(), 50u);
  // The steady arms' largest uplift as stats.json has it (the pass's record at every step).
  std::map<long long, double> stats_uplift;
  {
    std::ifstream in(dir + "/offline/stats.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    for (const auto& a : j.at("steady_arms")) stats_uplift[std::llround(1e3 * a.at("station_m").get<double>())] = a.at("max_uplift_m");
  }
  ASSERT_GE(stats_uplift.size(), 5u);
  // The bag's line_state carries them (written by the same run, from the same record: equal).
  for (const auto& [key, up] : stats_uplift) {
    ASSERT_TRUE(bag_uplift.count(key)) << "no line_state for the steady arm at " << key << " mm";
    EXPECT_EQ(bag_uplift[key], up) << "steady arm at " << key << " mm";
  }

  ros::NodeHandle nh;
  ros::Publisher status = nh.advertise<std_msgs::String>("pass_status", 1, true);
  ros::Subscriber sub = nh.subscribe("markers", 1000, &on_markers);
  // plot_contact_force, headless, on the same playback (started here: the PNG goes to this test's directory).
  ASSERT_EQ(std::system(sh(test_scenes::script("plot_contact_force") + " _output_png:=" + png + " _output_csv:=" + csv +
                           " _headless:=true > " + dir + "/plot.log 2>&1 & echo $! > " + dir + "/plot.pid")
                            .c_str()),
            0);
  ASSERT_TRUE(wait_for([&] { return sub.getNumPublishers() > 0; }, 60.0)) << "replay_markers did not start";
  ASSERT_TRUE(wait_for([&] { return status.getNumSubscribers() > 0; }, 60.0))
      << "plot_contact_force did not start; see " << dir << "/plot.log";
  ros::WallDuration(1.0).sleep();  // its other subscriptions connect

  ASSERT_EQ(std::system(sh("rosbag play -q --clock -r 2 -d 1 " + bag + " > " + dir + "/play.log 2>&1").c_str()), 0)
      << "see " << dir << "/play.log";
  ros::WallDuration(2.0).sleep();  // the last messages reach the nodes

  std::vector<visualization_msgs::MarkerArray> got;
  {
    std::lock_guard<std::mutex> l(mu);
    got = received;
  }
  // One marker array per wire_shape; the first ones may go while the connections are made.
  EXPECT_GE(got.size(), shape_stamps.size() * 8 / 10) << "of " << shape_stamps.size() << " wire shapes";
  EXPECT_LE(got.size(), shape_stamps.size());
  ASSERT_FALSE(got.empty());
  double first_x = 1e300, last_x = -1e300;
  for (const auto& arr : got) {
    std::map<std::string, std::size_t> points;  // per namespace
    ros::Time stamp;
    const visualization_msgs::Marker* head = nullptr;
    for (const auto& mk : arr.markers) {
      points[mk.ns] += mk.points.size();
      stamp = mk.header.stamp;
      EXPECT_EQ(mk.header.frame_id, "line");
      if (mk.ns == "pantograph_head") head = &mk;
    }
    for (const char* ns : {"wires", "droppers", "masts", "steady_arms", "pantograph_frame", "contact_force"})
      EXPECT_GT(points[ns], 0u) << ns << " at " << stamp;
    ASSERT_TRUE(shape_stamps.count(stamp)) << "marker stamp " << stamp << " is no wire_shape's";
    ASSERT_TRUE(head);
    // Drawn at the recorded position of that instant (same arithmetic up to rounding: 1e-9 m).
    ASSERT_TRUE(position.count(stamp));
    EXPECT_NEAR(head->pose.position.x, position[stamp], 1e-9) << "at " << stamp;
    first_x = std::min(first_x, head->pose.position.x);
    last_x = std::max(last_x, head->pose.position.x);
  }
  // The whole pass was drawn, not only its start.
  EXPECT_GT(last_x - first_x, 400.0);

  // The pass ends (the offline bag has no pass_status: sent here as the node would): the plot is written.
  std_msgs::String ended;
  ended.data = "ended";
  status.publish(ended);
  const bool written = wait_for([&] { return std::ifstream(png).good(); }, 30.0);
  (void)!std::system(sh("kill -INT $(cat " + dir + "/plot.pid) 2>/dev/null; sleep 1").c_str());
  ASSERT_TRUE(written) << png << " not written; see " << dir << "/plot.log";
  std::ifstream f(png, std::ios::binary);
  unsigned char head[24] = {};
  f.read(reinterpret_cast<char*>(head), sizeof head);
  ASSERT_EQ(std::string(reinterpret_cast<char*>(head + 1), 3), "PNG");
  // IHDR: width and height, big-endian, of the 11 x 6.5 in figure at 100 dpi.
  const unsigned w = head[16] << 24 | head[17] << 16 | head[18] << 8 | head[19];
  const unsigned h = head[20] << 24 | head[21] << 16 | head[22] << 8 | head[23];
  EXPECT_EQ(w, 1100u);
  EXPECT_EQ(h, 650u);
  // The uplift it plots is stats.json's at every steady arm of the analysis section. Exact: the
  // values travel as doubles (line_state) and are written with repr. Sampling the 10 Hz wire shape
  // instead reads up to a quarter less (the arm's peak falls between two shapes at 300 km/h).
  std::ifstream table(csv);
  ASSERT_TRUE(table.good()) << csv << " not written; see " << dir << "/plot.log";
  std::map<long long, double> plotted;
  std::string line;
  std::getline(table, line);
  EXPECT_EQ(line, "station_m,max_uplift_m,uplift_now_m");
  while (std::getline(table, line)) {
    const double x = std::stod(line.substr(0, line.find(',')));
    const std::string rest = line.substr(line.find(',') + 1);
    plotted[std::llround(1e3 * x)] = std::stod(rest.substr(0, rest.find(',')));
  }
  for (const auto& [key, up] : stats_uplift) {
    ASSERT_TRUE(plotted.count(key)) << "the plot has no steady arm at " << key << " mm";
    EXPECT_EQ(plotted[key], up) << "steady arm at " << key << " mm";
  }

  // A second recording, of another kind of line (stitched: stitch wires the first lacks), played
  // into the same replay_markers: what the first drew is deleted before the second is drawn
  // (markers have no lifetime; the first line's parts stayed), and the second is drawn whole.
  const std::string bag2 = dir + "/stitched.bag";
  ASSERT_EQ(std::system((test_scenes::program("simulate_pass") + " --scene " + test_scenes::kReferenceStitched +
                         " --set line.span_count=4 --quiet --out " + dir + "/offline2 --bag " + bag2 + " > " + dir +
                         "/simulate_pass2.log 2>&1").c_str()),
            0)
      << "see " << dir << "/simulate_pass2.log";
  {
    std::lock_guard<std::mutex> l(mu);
    received.clear();
  }
  ASSERT_EQ(std::system(sh("rosbag play -q --clock -r 2 -d 1 " + bag2 + " > " + dir + "/play2.log 2>&1").c_str()), 0)
      << "see " << dir << "/play2.log";
  ros::WallDuration(2.0).sleep();
  {
    std::lock_guard<std::mutex> l(mu);
    got = received;
  }
  ASSERT_GE(got.size(), 2u);
  ASSERT_FALSE(got.front().markers.empty());
  EXPECT_EQ(got.front().markers.front().action, visualization_msgs::Marker::DELETEALL) << "the first line's drawing stayed";
  std::size_t stitch_points = 0;
  for (const auto& mk : got.back().markers)
    if (mk.ns == "wires") stitch_points += mk.points.size();
  EXPECT_GT(stitch_points, 0u);
  if (!HasFailure()) (void)!std::system(("rm -rf " + dir).c_str());  // kept for a look when it failed
}

int main(int argc, char** argv) { return ros_test::ros_test_main(argc, argv, "test_replay_node", 1); }
