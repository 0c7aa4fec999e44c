// rostest companion of node.test: the live node with the reference scene at real time.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <rosgraph_msgs/Clock.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <std_msgs/Float64.h>
#include <std_msgs/Float64MultiArray.h>
#include <std_srvs/SetBool.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <functional>
#include <limits>
#include <mutex>
#include <vector>

#include "catenary_sim/ContactForceArray.h"
#include "catenary_sim/PantographStateArray.h"
#include "catenary_sim/Step.h"
#include "catenary_sim/WireShapeArray.h"
#include "ros_test_support.hpp"

using namespace catenary_sim;

using ros_test::Recorder;
using ros_test::wait_for;

namespace {

PantographStateArray latest_state(Recorder<PantographStateArray>& r) {
  r.clear();
  EXPECT_TRUE(wait_for([&] { return r.size() > 0; }, 5.0));
  return r.take().back();
}

void send_speed(double v) {
  static ros::Publisher pub = ros::NodeHandle().advertise<std_msgs::Float64>("cmd/train_speed", 1);
  ASSERT_TRUE(wait_for([&] { return pub.getNumSubscribers() > 0; }, 5.0));
  std_msgs::Float64 m;
  m.data = v;
  pub.publish(m);
}

bool set_paused(bool p) {
  std_srvs::SetBool s;
  s.request.data = p;
  return ros::service::call("/catenary_sim/set_paused", s) && s.response.success;
}

}  // namespace

TEST(Node, EveryTopicPublishesWithIncreasingStamps) {
  Recorder<ContactForceArray> force("contact_force");
  Recorder<PantographStateArray> state("pantograph_state");
  Recorder<WireShapeArray> shape("wire_shape");
  Recorder<visualization_msgs::MarkerArray> markers("markers");
  Recorder<diagnostic_msgs::DiagnosticArray> diag("/diagnostics");
  ASSERT_TRUE(wait_for([&] { return shape.size() >= 5 && markers.size() >= 5 && force.size() >= 50 &&
                                    state.size() >= 50 && diag.size() >= 1; }, 15.0))
      << force.size() << " " << state.size() << " " << shape.size() << " " << markers.size() << " " << diag.size();
  auto increasing = [](const std::vector<ros::Time>& t, const char* what) {
    for (std::size_t i = 1; i < t.size(); ++i) EXPECT_GT(t[i], t[i - 1]) << what << " message " << i;
  };
  std::vector<ros::Time> t;
  for (const auto& m : force.take()) {
    t.push_back(m.header.stamp);
    ASSERT_EQ(m.pantographs.size(), 1u);
    EXPECT_EQ(m.pantographs[0].name, "leading");
    EXPECT_EQ(m.header.frame_id, "line");
  }
  increasing(t, "contact_force");
  t.clear();
  for (const auto& m : state.take()) {
    t.push_back(m.header.stamp);
    ASSERT_EQ(m.pantographs.size(), 1u);
    EXPECT_EQ(m.pantographs[0].displacement.size(), 3u);
  }
  increasing(t, "pantograph_state");
  t.clear();
  for (const auto& m : shape.take()) {
    t.push_back(m.header.stamp);
    ASSERT_EQ(m.wires.size(), 2u);  // contact wire and messenger
    EXPECT_GT(m.wires[0].stations.size(), 500u);
  }
  increasing(t, "wire_shape");
  t.clear();
  for (const auto& m : markers.take()) {
    ASSERT_FALSE(m.markers.empty());
    t.push_back(m.markers[0].header.stamp);
  }
  increasing(t, "markers");
  bool found = false;
  for (const auto& a : diag.take())
    for (const auto& s : a.status)
      if (s.name.find("simulation") != std::string::npos) found = true;
  EXPECT_TRUE(found) << "no diagnostics status named ...simulation";
}

TEST(Node, TopicsPublishAtTheirDeclaredRates) {
  // node.test declares publish_rate 100 Hz and shape_rate 10 Hz; markers go at the default
  // marker_rate of 30 Hz while someone listens. Counted over 3 s of wall time; the lower bound
  // leaves room for a loaded CI machine (the node drops ticks rather than stretching dt), the
  // upper one catches a rate parameter that is ignored.
  Recorder<ContactForceArray> force("contact_force");
  Recorder<WireShapeArray> shape("wire_shape");
  Recorder<visualization_msgs::MarkerArray> markers("markers");
  ASSERT_TRUE(wait_for([&] { return markers.size() > 0 && shape.size() > 0; }, 10.0));
  force.clear();
  shape.clear();
  markers.clear();
  const double window = 3.0;
  ros::WallDuration(window).sleep();
  const double f = force.size() / window, w = shape.size() / window, k = markers.size() / window;
  EXPECT_GT(f, 0.6 * 100.0) << f;
  EXPECT_LT(f, 1.2 * 100.0) << f;
  EXPECT_GT(w, 0.6 * 10.0) << w;
  EXPECT_LT(w, 1.2 * 10.0 + 1.0) << w;
  EXPECT_GT(k, 0.6 * 30.0) << k;
  EXPECT_LT(k, 1.2 * 30.0) << k;
}

TEST(Node, TfLineToPantographHead) {
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  std::string err;
  ASSERT_TRUE(buffer.canTransform("line", "pantograph_leading", ros::Time(0), ros::Duration(5.0), &err)) << err;
  const auto t = buffer.lookupTransform("line", "pantograph_leading", ros::Time(0));
  EXPECT_GT(t.transform.translation.z, 4.5);  // head at the contact wire, 5.3 m nominal
  EXPECT_LT(t.transform.translation.z, 6.0);
  EXPECT_GE(t.transform.translation.x, -1.0);
}

TEST(Node, SpeedCommandRampsAtConfiguredAcceleration) {
  Recorder<PantographStateArray> state("pantograph_state");
  const PantographStateArray s0 = latest_state(state);
  ASSERT_NEAR(s0.max_acceleration, 5.0, 1e-12);
  const double v0 = s0.speed;
  const double target = v0 - 4.0;  // 0.8 s at 5 m/s^2
  send_speed(target);
  ASSERT_TRUE(wait_for([&] { auto v = state.take(); return !v.empty() && v.back().speed == target; }, 10.0));
  // Samples strictly inside the ramp: dv/dt between any two of them is -5 m/s^2 (stamps are sim time).
  std::vector<PantographStateArray> ramp;
  for (const auto& m : state.take())
    if (m.speed < v0 - 0.05 && m.speed > target + 0.05) ramp.push_back(m);
  ASSERT_GE(ramp.size(), 5u);
  const auto& a = ramp.front();
  const auto& b = ramp.back();
  const double accel = (b.speed - a.speed) / (b.header.stamp - a.header.stamp).toSec();
  EXPECT_NEAR(accel, -5.0, 0.05);
  EXPECT_DOUBLE_EQ(b.target_speed, target);
}

TEST(Node, NanSpeedCommandIsRejected) {
  Recorder<PantographStateArray> state("pantograph_state");
  const PantographStateArray s0 = latest_state(state);
  ASSERT_EQ(s0.speed, s0.target_speed) << "still ramping";
  send_speed(std::numeric_limits<double>::quiet_NaN());
  send_speed(-3.0);
  ros::WallDuration(0.5).sleep();
  const PantographStateArray s1 = latest_state(state);
  EXPECT_GT(s1.header.stamp, s0.header.stamp);  // still running
  EXPECT_EQ(s1.speed, s0.speed);
  EXPECT_EQ(s1.target_speed, s0.target_speed);
  EXPECT_TRUE(std::isfinite(s1.speed));
}

TEST(Node, PausedStepAdvancesExactlyN) {
  Recorder<PantographStateArray> state("pantograph_state");
  ASSERT_TRUE(set_paused(true));
  // Running: step is rejected (checked after pausing would not test it, so unpause first).
  ASSERT_TRUE(set_paused(false));
  Step running;
  running.request.steps = 10;
  ASSERT_TRUE(ros::service::call("/catenary_sim/step", running));
  EXPECT_FALSE(running.response.success);
  EXPECT_EQ(running.response.steps_advanced, 0);

  ASSERT_TRUE(set_paused(true));
  const PantographStateArray p0 = latest_state(state);
  ros::WallDuration(0.3).sleep();
  const PantographStateArray p1 = latest_state(state);
  EXPECT_EQ(p1.step, p0.step) << "time advanced while paused";
  EXPECT_EQ(p1.header.stamp, p0.header.stamp);

  for (int bad : {0, -1, 100001}) {
    Step s;
    s.request.steps = bad;
    ASSERT_TRUE(ros::service::call("/catenary_sim/step", s));
    EXPECT_FALSE(s.response.success) << bad;
    EXPECT_EQ(s.response.total_steps, p1.step) << bad;
  }

  const int n = 250;
  Step s;
  s.request.steps = n;
  state.clear();
  ASSERT_TRUE(ros::service::call("/catenary_sim/step", s));
  EXPECT_TRUE(s.response.success) << s.response.message;
  EXPECT_EQ(s.response.steps_advanced, n);
  EXPECT_EQ(s.response.total_steps, p1.step + n);
  ASSERT_TRUE(wait_for([&] { auto v = state.take(); return !v.empty() && v.back().step == p1.step + n; }, 5.0));
  const PantographStateArray p2 = state.take().back();
  const double dt = (p2.sim_time - p1.sim_time) / n;
  EXPECT_GT(dt, 0.0);
  EXPECT_NEAR((p2.header.stamp - p1.header.stamp).toSec(), n * dt, 1e-6);
  ros::WallDuration(0.3).sleep();
  EXPECT_EQ(latest_state(state).step, p1.step + n) << "advanced more than N while paused";
  ASSERT_TRUE(set_paused(false));
  ASSERT_TRUE(wait_for([&] { auto v = state.take(); return !v.empty() && v.back().step > p1.step + n; }, 5.0));
}

namespace {
void send_uplift(const std::vector<double>& values) {
  static ros::Publisher pub = ros::NodeHandle().advertise<std_msgs::Float64MultiArray>("cmd/uplift_force", 1);
  ASSERT_TRUE(wait_for([&] { return pub.getNumSubscribers() > 0; }, 5.0));
  std_msgs::Float64MultiArray m;
  m.data = values;
  pub.publish(m);
}

bool reset_pass() {
  std_srvs::Trigger t;
  return ros::service::call("/catenary_sim/reset", t) && t.response.success;
}

// Mean total contact force while the pantograph is in [x0, x1] m, over the next pass from a reset.
double mean_force_over(Recorder<ContactForceArray>& forces, double x0, double x1) {
  EXPECT_TRUE(reset_pass());
  forces.clear();
  EXPECT_TRUE(wait_for([&] { auto v = forces.take(); return !v.empty() && v.back().pantographs[0].position > x1; }, 60.0));
  double sum = 0.0;
  int n = 0;
  for (const auto& m : forces.take()) {
    const double x = m.pantographs[0].position;
    if (x >= x0 && x <= x1) {
      sum += m.pantographs[0].total;
      ++n;
    }
  }
  EXPECT_GT(n, 50);
  return n ? sum / n : std::nan("");
}

}  // namespace

TEST(Node, RejectedUpliftCommandsLeaveTheUpliftUnchanged) {
  Recorder<PantographStateArray> state("pantograph_state");
  const PantographStateArray s0 = latest_state(state);
  send_uplift({std::numeric_limits<double>::quiet_NaN()});
  send_uplift({-5.0});
  send_uplift({100.0, 100.0});  // the scene has one pantograph: two values are rejected
  ros::WallDuration(0.5).sleep();
  const PantographStateArray s1 = latest_state(state);
  EXPECT_GT(s1.header.stamp, s0.header.stamp);
  EXPECT_EQ(s1.pantographs[0].uplift, s0.pantographs[0].uplift);
}

// Two passes over the same stretch from a reset, before and after an uplift command: the mean
// contact force rises by the uplift step less what the roof spring (160 N/m) takes back as the
// head works higher: at most 160 N/m x 100 N x 0.5 mm/N (the catenary's elasticity) = 8 N. The
// passes are otherwise identical (same speed, same start), so 2 N more covers the rest.
TEST(Node, UpliftCommandRaisesTheMeanContactForceAndResetStartsANewPass) {
  Recorder<ContactForceArray> forces("contact_force");
  Recorder<PantographStateArray> state("pantograph_state");
  const PantographStateArray before = latest_state(state);
  const double f100 = mean_force_over(forces, 110.0, 330.0);
  send_uplift({200.0});
  ASSERT_TRUE(wait_for([&] { auto v = state.take(); return !v.empty() && v.back().pantographs[0].uplift == 200.0; }, 5.0));
  const PantographStateArray after_cmd = latest_state(state);
  const double f200 = mean_force_over(forces, 110.0, 330.0);
  EXPECT_LE(f200 - f100, 100.0 + 2.0);
  EXPECT_GE(f200 - f100, 100.0 - 8.0 - 2.0);
  // Reset: a new pass from the start while time keeps running.
  ASSERT_TRUE(reset_pass());
  const PantographStateArray fresh = latest_state(state);
  EXPECT_LT(fresh.train_front, after_cmd.train_front + 1e-9);
  EXPECT_LT(fresh.train_front, 60.0);
  EXPECT_GT(fresh.header.stamp, before.header.stamp);
  EXPECT_GT(fresh.sim_time, after_cmd.sim_time);
  send_uplift({100.0});
}

// The live marker array never holds an empty list marker (rviz would mark the display Error):
// over two seconds of a pass, every LINE_LIST / LINE_STRIP / POINTS added has points.
TEST(Node, LiveMarkersHaveNoEmptyListMarker) {
  using visualization_msgs::Marker;
  Recorder<visualization_msgs::MarkerArray> markers("markers");
  ASSERT_TRUE(wait_for([&] { return markers.size() >= 20; }, 10.0)) << markers.size();
  std::size_t lists = 0;
  for (const auto& arr : markers.take())
    for (const Marker& mk : arr.markers) {
      const bool list = mk.type == Marker::LINE_LIST || mk.type == Marker::LINE_STRIP || mk.type == Marker::POINTS;
      if (list && mk.action == Marker::ADD) {
        ++lists;
        EXPECT_FALSE(mk.points.empty()) << mk.ns << "/" << mk.id;
      }
    }
  EXPECT_GT(lists, 20u);
}

// gazebo_ros behaviour: /clock keeps coming while paused (at shape_rate, 10 Hz here) with the
// paused time, so that a /use_sim_time node started during a pause gets its time at once.
TEST(Node, ClockIsPublishedWhilePausedAtThePausedTime) {
  Recorder<rosgraph_msgs::Clock> clock("/clock");
  Recorder<PantographStateArray> state("pantograph_state");
  ASSERT_TRUE(wait_for([&] { return clock.size() > 10; }, 5.0)) << "no /clock while running";
  ASSERT_TRUE(set_paused(true));
  const PantographStateArray paused = latest_state(state);
  ros::WallDuration(0.3).sleep();  // anything sent before the pause has arrived
  clock.clear();
  ros::WallDuration(1.5).sleep();
  const std::vector<rosgraph_msgs::Clock> during = clock.take();
  // 10 Hz for 1.5 s: 15 expected; 3 leaves room for a loaded machine, and 0 is the defect.
  EXPECT_GE(during.size(), 3u) << "/clock fell silent while paused";
  for (const auto& c : during) EXPECT_EQ(c.clock, paused.header.stamp) << "the clock moved while paused";
  // Stamps are simulated time (no wall-clock offset): the stamp is the pantograph state's sim time.
  EXPECT_NEAR(paused.header.stamp.toSec(), paused.sim_time, 1e-6);
  ASSERT_TRUE(set_paused(false));
  ASSERT_TRUE(wait_for([&] { auto v = clock.take(); return !v.empty() && v.back().clock > paused.header.stamp; }, 5.0));
}

namespace {
bool reconfigure(const std::string& name, double value) {
  dynamic_reconfigure::Reconfigure r;
  dynamic_reconfigure::DoubleParameter p;
  p.name = name;
  p.value = value;
  r.request.config.doubles.push_back(p);
  if (!ros::service::call("/catenary_sim/set_parameters", r)) return false;
  for (const auto& d : r.response.config.doubles)
    if (d.name == name) return d.value == value;
  return false;
}
}  // namespace

// dynamic_reconfigure: real_time_factor 0.25 makes simulated time advance at a quarter of the wall
// clock. Pacing never runs ahead of the factor (steps_due), so the rate is at most 0.25 plus one
// tick of 10 ms over the 2 s measured; on a loaded machine it can only fall behind, and below half
// of it would take a second of stalls (then overruns, which the diagnostics report).
TEST(Node, DynamicReconfigureChangesTheRealTimeFactorLive) {
  Recorder<PantographStateArray> state("pantograph_state");
  ASSERT_TRUE(reconfigure("real_time_factor", 0.25));
  ros::WallDuration(0.3).sleep();
  const PantographStateArray a = latest_state(state);
  const ros::WallTime wa = ros::WallTime::now();
  ros::WallDuration(2.0).sleep();
  const PantographStateArray b = latest_state(state);
  const double wall = (ros::WallTime::now() - wa).toSec();
  const double rate = (b.sim_time - a.sim_time) / wall;
  EXPECT_LE(rate, 0.25 * (2.0 + 0.01 + 0.1) / 2.0) << "faster than the factor";  // +0.1 s: latest_state's latency
  EXPECT_GE(rate, 0.125) << "far slower than the factor";
  ASSERT_TRUE(reconfigure("real_time_factor", 1.0));
  // Out of range: dynamic_reconfigure clamps to the .cfg's range, which is the parameter's.
  dynamic_reconfigure::Reconfigure r;
  dynamic_reconfigure::DoubleParameter p;
  p.name = "max_acceleration";
  p.value = 1e9;
  r.request.config.doubles.push_back(p);
  ASSERT_TRUE(ros::service::call("/catenary_sim/set_parameters", r));
  for (const auto& d : r.response.config.doubles) {
    if (d.name == "max_acceleration") {
      EXPECT_LE(d.value, 20.0);
    }
  }
  ASSERT_TRUE(reconfigure("max_acceleration", 5.0));
}

// dynamic_reconfigure clamps a value to the .cfg's range, but NaN passes its clamp (it compares
// false either way). Each field must refuse it and answer with the value in effect, and the pass
// must go on: a NaN publish_rate stopped the node ("Duration is out of dual 32-bit range"), a NaN
// real_time_factor froze the pass, a NaN scale drew NaN markers.
TEST(Node, DynamicReconfigureRefusesNaN) {
  dynamic_reconfigure::Reconfigure now;
  ASSERT_TRUE(ros::service::call("/catenary_sim/set_parameters", now));  // (an empty request: the config in effect)
  for (const dynamic_reconfigure::DoubleParameter& before : now.response.config.doubles) {
    SCOPED_TRACE(before.name);
    ASSERT_TRUE(std::isfinite(before.value));
    dynamic_reconfigure::Reconfigure r;
    dynamic_reconfigure::DoubleParameter p;
    p.name = before.name;
    p.value = std::nan("");
    r.request.config.doubles.push_back(p);
    ASSERT_TRUE(ros::service::call("/catenary_sim/set_parameters", r));
    bool answered = false;
    for (const auto& d : r.response.config.doubles)
      if (d.name == before.name) {
        EXPECT_EQ(d.value, before.value) << "not the value in effect";
        answered = true;
      }
    EXPECT_TRUE(answered);
  }
  Recorder<PantographStateArray> state("pantograph_state");
  const PantographStateArray a = latest_state(state);
  ros::WallDuration(0.5).sleep();
  const PantographStateArray b = latest_state(state);
  EXPECT_NE(b.sim_time, a.sim_time) << "the pass stopped";  // (at_end loop: it may have started again)
}

int main(int argc, char** argv) { return ros_test::ros_test_main(argc, argv, "test_catenary_sim_node"); }
