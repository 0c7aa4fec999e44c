// rostest companion of hil.test (1 kHz), hil_2khz.test, hil_inprocess.test and hil_udp.test (the
// loop over UDP with catenary_sim_hil_udp_node and virtual_rig ~transport udp: the contact points
// here are its monitoring topic, fed through the lock-free ring, which must lose none):
// catenary_sim_hil_node and virtual_rig close the loop over the topics, on the wall clock, on
// config/reference_55m_hil.yaml (the whole 550 m pass at 300 km/h: 6.6 s).
//
// What the wall clock does to the loop is its delay: the force applied in a period is the rig's
// answer to the contact point of one period before (the design point) or, when the answer was not
// there in time, to an older one, held (`measurement_step` in each contact point names it). On a
// loaded 2-core machine (a build beside the test) 5 to 20 % of the periods ran with an older
// answer, in stalls of up to 9 periods at 1 kHz and 26 at 2 kHz, and these alone moved the
// 20 Hz filtered mean of the pass by -0.23 to +0.09 N (0.76 N seen on a CI machine), with a sign
// and size that depend on where the stalls fall (the held force kicks the line and the
// pantograph; the effect is not a function of the mean delay: capping the same stalls at 1 period
// leaves -0.05 N of -0.22 N). A comparison with the internal pantograph under a fixed tolerance
// therefore failed by chance. Instead the test compares like with like:
//  1. it replays the pass offline with the same code (the core with the external pantograph, the
//     virtual rig's RigPantograph stepped as virtual_rig steps it) and the delay sequence the
//     live loop had: the live contact points must be reproduced period by period (the same
//     numbers through the same operations: a difference is a defect of the node, the rig or the
//     transport, e.g. a force applied that is not the answer it names, or a lost contact point);
//  2. the same replay with every answer in time (no delay) must give the statistics of the
//     internal lumped pantograph of config/reference_55m.yaml within test_hil.cpp's tolerance of
//     a loop delay of up to two periods (0.1 N on the mean, 1 % on the standard deviation).
// The delay the machine imposed and its effect on the statistics (live - no delay) are recorded in
// the summary property.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "catenary_sim/ContactPointArray.h"
#include "catenary_sim/MeasuredContactForce.h"
#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "catenary_sim/ros/hil.hpp"
#include "catenary_sim/ros/virtual_rig.hpp"
#include "../hil/hil_test_support.hpp"
#include "ros_test_support.hpp"

using namespace catenary_sim;
using namespace catenary_sim::ros_layer;
using namespace hil_test;

namespace {

std::mutex mu;
std::vector<ContactPointArray> points;
bool ended = false;
std::vector<std::string> measurement_frames;  // header.frame_id of every hil/contact_force from the rig

void on_point(const ContactPointArray::ConstPtr& m) {
  std::lock_guard<std::mutex> l(mu);
  points.push_back(*m);
  if (m->mode == ContactPointArray::ENDED) ended = true;
}

void on_measurement(const MeasuredContactForce::ConstPtr& m) {
  std::lock_guard<std::mutex> l(mu);
  measurement_frames.push_back(m->header.frame_id);
}

// The loop replayed offline (hil_test_support.hpp) with the contact points as the node publishes them.
bool replay(double dt, int k, const std::vector<std::uint64_t>* measurement_step, Series& out, std::string& error) {
  std::vector<ContactPointMotion> scratch;
  return hil_test::replay(dt, k, measurement_step, out, error, [&scratch](const Model& m, const State& s, int steps) {
    const ContactPointArray msg = to_contact_points(m, s, ros::Time(1), "line", steps, scratch);
    return Observed{msg.step, msg.speed, msg.pantographs[0].position, msg.pantographs[0].applied_force,
                    wire_points(msg.pantographs[0])};
  });
}

}  // namespace

TEST(HilLoop, LiveLoopIsItsOwnReplayAndWithoutDelayTheInternalPantograph) {
  ros::NodeHandle pnh("~");
  double rate = 0.0;
  ASSERT_TRUE(pnh.getParam("rate", rate));
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(90.0);
  while (ros::ok() && ros::WallTime::now() < deadline) {
    {
      std::lock_guard<std::mutex> l(mu);
      if (ended) break;
    }
    ros::WallDuration(0.05).sleep();
  }
  std::vector<ContactPointArray> msgs;
  std::vector<std::string> frames;
  {
    std::lock_guard<std::mutex> l(mu);
    msgs = points;
    frames = measurement_frames;
    ASSERT_TRUE(ended) << "the pass did not end within 90 s (" << points.size() << " contact points)";
  }
  // Every contact point finite; the running ones one period apart, in order, with increasing stamps.
  std::vector<const ContactPointArray*> run;
  for (const ContactPointArray& m : msgs) {
    EXPECT_TRUE(ros_layer::all_finite(m)) << "step " << m.step;
    EXPECT_NE(m.mode, ContactPointArray::SAFE_HOLD) << "step " << m.step;
    if (m.mode == ContactPointArray::RUNNING || (m.mode == ContactPointArray::ENDED && run.size() && m.step > run.back()->step))
      run.push_back(&m);
  }
  ASSERT_GT(run.size(), 100u);
  // The rig answers in the frame of the contact points (the line frame), never an empty frame_id
  // (over UDP, hil_udp.test, the measurements are packets: not on a topic).
  bool on_topic = true;
  pnh.param("measurements_on_topic", on_topic, true);
  if (on_topic) ASSERT_FALSE(frames.empty());
  else EXPECT_TRUE(frames.empty()) << "hil/contact_force published although the rig speaks UDP";
  for (const std::string& f : frames) ASSERT_EQ(f, msgs[0].header.frame_id);
  EXPECT_FALSE(msgs[0].header.frame_id.empty());
  const int k = static_cast<int>(run[0]->steps_per_period);
  const double dt = run[0]->dt;
  EXPECT_NEAR(k * dt, 1.0 / rate, 1e-12);
  std::size_t gaps = 0;
  for (std::size_t i = 1; i < run.size(); ++i) {
    EXPECT_GT(run[i]->header.stamp, run[i - 1]->header.stamp);
    gaps += run[i]->step != run[i - 1]->step + k;
  }
  // (the node queues a second of contact points for a slow subscriber: none is lost short of a
  // stall of that length, and the replay needs the measurement_step of every period)
  ASSERT_EQ(gaps, 0u) << "contact points lost on the way to the test";

  // 1. The live loop is the replay of its own delays.
  Series live;
  std::vector<std::uint64_t> used;
  std::map<long long, std::size_t> late;  // periods of delay beyond the design point -> count
  for (const ContactPointArray* c : run) {
    live.step.push_back(c->step);
    live.x.push_back(c->pantographs[0].position);
    live.f.push_back(c->pantographs[0].applied_force);
    used.push_back(c->measurement_step);
    ++late[(static_cast<long long>(c->step) - static_cast<long long>(c->measurement_step)) / k - 1];
  }
  Series same, prompt;
  std::string error;
  ASSERT_TRUE(replay(dt, k, &used, same, error)) << error;
  ASSERT_EQ(same.step.size(), live.step.size()) << "periods in the replay and in the live pass";
  // The same numbers through the same operations (TCPROS carries the float64 values exactly): the
  // differences are round-off at most (1e-6 N: far below any force a defect would change).
  std::size_t differ = 0, first = 0;
  for (std::size_t i = 0; i < live.f.size(); ++i) {
    const bool d = same.step[i] != live.step[i] || std::fabs(same.x[i] - live.x[i]) > 1e-9 ||
                   std::fabs(same.f[i] - live.f[i]) > 1e-6;
    if (d && differ++ == 0) first = i;
  }
  EXPECT_EQ(differ, 0u) << "periods where the live loop is not its replay; first: step " << live.step[first]
                        << " (replay " << same.step[first] << "), applied force " << live.f[first] << " N (replay "
                        << same.f[first] << " N), using the answer to step " << used[first];

  // 2. Without the delay the loop is the internal pantograph.
  ASSERT_TRUE(replay(dt, k, nullptr, prompt, error)) << error;
  Simulation internal(scene_with_dt("reference_55m.yaml", dt));
  ASSERT_NEAR(internal.state().speed, run.back()->speed, 1e-9);
  const Model& m = internal.model();
  auto stats = [&](const Series& s) { return section_stats(m, s, rate); };
  const ForceStatistics sl = stats(live), sp = stats(prompt), si = stats(internal_series(dt, k));
  // test_hil.cpp, ClosedLoop.DelayOfOneOrTwoPeriodsChangesTheStatisticsLittle (1 kHz) and
  // WithoutDelayTheLoopIsTheInternalPantograph (2 kHz: equal but for round-off).
  EXPECT_NEAR(sp.mean, si.mean, 0.1);
  EXPECT_NEAR(sp.std_dev, si.std_dev, 0.01 * si.std_dev);

  std::string hist;
  std::size_t delayed = 0;
  for (const auto& [d, n] : late) {
    hist += (hist.empty() ? "" : " ") + std::to_string(d) + ":" + std::to_string(n);
    if (d > 0) delayed += n;
  }
  char summary[768];
  std::snprintf(summary, sizeof summary,
                "%g Hz (%d x %g ms), %zu periods: %.1f %% with an older answer than the design point (periods late: "
                "count %s); live mean %.3f N std %.3f N; without delay mean %.3f N std %.3f N; internal mean %.3f N "
                "std %.3f N; the delay's effect: mean %+.3f N, std %+.2f %%",
                rate, k, dt * 1e3, run.size(), 100.0 * delayed / run.size(), hist.c_str(), sl.mean, sl.std_dev, sp.mean,
                sp.std_dev, si.mean, si.std_dev, sl.mean - sp.mean, 100.0 * (sl.std_dev / sp.std_dev - 1.0));
  RecordProperty("summary", summary);
  ROS_INFO("test_hil_loop: %s", summary);
}

int main(int argc, char** argv) {
  ros_test::init(argc, argv, "test_hil_loop");
  ros::NodeHandle nh;
  ros::Subscriber sub =
      nh.subscribe("hil/contact_point", 100000, &on_point, ros::TransportHints().tcpNoDelay());
  ros::Subscriber msub = nh.subscribe("hil/contact_force", 100000, &on_measurement);
  return ros_test::run_all_tests(1);
}
