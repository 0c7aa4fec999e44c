// rostest companion of hil_services.test: catenary_sim_hil_node (1 kHz, ~hil/auto_start false)
// with this test as the rig. Each service is called in a state that refuses it (success false, a
// message saying why, and the state as it was: mode, step, pass_count) and in one that allows it,
// and its effect is read on hil/contact_point: ~arm starts the pass, ~set_paused holds the line
// (the step and the simulation time stand, the wall-clock stamps go on), ~reset starts a new pass
// from the start with time running on, cmd/train_speed changes the speed (a bad one is rejected),
// ~stop ends the pass through the safe hold with the statistics written, and ~arm after the end
// starts a new pass without a relaunch. Timeouts are generous (a loaded 2-core machine): the test
// waits for effects, it never times them.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <std_msgs/Float64.h>
#include <std_srvs/SetBool.h>
#include <std_srvs/Trigger.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "catenary_sim/ContactPointArray.h"
#include "catenary_sim/MeasuredContactForce.h"
#include "catenary_sim/ros/hil.hpp"
#include "hil_rig.hpp"
#include "ros_test_support.hpp"

using namespace catenary_sim;

namespace {

using hil_rostest::point;
using hil_rostest::wait_for;

// What the test hears of the node (made in main, after ros::init): its contact points and its
// ERROR lines on /rosout.
struct Heard : hil_rostest::HeardPoints {
  ros_test::NodeLog errors{"catenary_sim_hil"};
};
Heard* heard = nullptr;

// A contact point that arrived after now (the node has run a period since).
ContactPointArray next_point() {
  const ros::WallTime since = ros::WallTime::now();
  EXPECT_TRUE(wait_for([&] { return heard->points.last_with_arrival().second > since; }, 10.0)) << "no contact point for 10 s";
  return point();
}

bool mode_is(std::uint8_t mode, double timeout_s = 10.0) {
  return wait_for([&] { return point().mode == mode; }, timeout_s);
}

const char* kNames[] = {"WAITING", "RUNNING", "SAFE_HOLD", "ENDED", "PAUSED"};
std::string name(std::uint8_t mode) { return mode < 5 ? kNames[mode] : "?"; }

std_srvs::Trigger::Response trigger(const std::string& service) {
  std_srvs::Trigger srv;
  EXPECT_TRUE(ros::service::call("/catenary_sim_hil/" + service, srv)) << service;
  return srv.response;
}

std_srvs::SetBool::Response set_paused(bool paused) {
  std_srvs::SetBool srv;
  srv.request.data = paused;
  EXPECT_TRUE(ros::service::call("/catenary_sim_hil/set_paused", srv));
  return srv.response;
}

// A refused call: success false, a message that says so, and nothing changed: the mode and
// pass_count unchanged and, where the line is held, the step too.
template <class Response>
void expect_refused(const Response& r, const ContactPointArray& before, bool held, const std::string& what) {
  EXPECT_FALSE(r.success) << what << ": " << r.message;
  EXPECT_EQ(r.message.rfind("refused: ", 0), 0u) << what << ": " << r.message;
  const ContactPointArray after = next_point();
  EXPECT_EQ(name(after.mode), name(before.mode)) << what;
  EXPECT_EQ(after.pass_count, before.pass_count) << what;
  if (held) {
    EXPECT_EQ(after.step, before.step) << what;
  }
}

}  // namespace

TEST(HilServices, ArmPauseSpeedResetStopAndArmAgain) {
  ros::NodeHandle nh, pnh("~");
  std::string stats_file;
  ASSERT_TRUE(pnh.getParam("stats_file", stats_file));
  std::remove(stats_file.c_str());
  ASSERT_TRUE(ros::service::waitForService("/catenary_sim_hil/arm", ros::Duration(30.0)));
  ASSERT_TRUE(wait_for([] { return point().steps_per_period > 0; }, 30.0)) << "no hil/contact_point";
  const ContactPointArray first = point();
  ros::Publisher speed_pub = nh.advertise<std_msgs::Float64>("cmd/train_speed", 10, true);

  // 1. ~hil/auto_start false: the rig sends, but the pass waits for ~arm.
  ros::WallDuration(1.0).sleep();
  ContactPointArray p = next_point();
  EXPECT_EQ(name(p.mode), "WAITING");
  EXPECT_EQ(p.step, first.step) << "stepped before ~arm";
  EXPECT_DOUBLE_EQ(p.pantographs.at(0).measurement_age, -1.0);
  // Nothing to pause, resume, reset or stop yet.
  expect_refused(set_paused(true), p, true, "set_paused true while waiting");
  expect_refused(set_paused(false), p, true, "set_paused false while waiting");
  expect_refused(trigger("reset"), p, true, "reset while waiting");
  expect_refused(trigger("stop"), p, true, "stop while waiting");

  // A speed commanded before the start is the speed the pass starts at (not ~speed_kmh's).
  EXPECT_NEAR(first.speed, 100.0 / 3.6, 1e-9);
  std_msgs::Float64 v;
  v.data = 15.0;
  speed_pub.publish(v);
  ASSERT_TRUE(wait_for([] { return point().speed == 15.0; }, 10.0)) << point().speed;
  EXPECT_EQ(name(point().mode), "WAITING");
  EXPECT_EQ(point().step, first.step);

  // 2. ~arm: the pass starts with the rig's measurements; a second ~arm is refused.
  std_srvs::Trigger::Response r = trigger("arm");
  EXPECT_TRUE(r.success) << r.message;
  ASSERT_TRUE(mode_is(ContactPointArray::RUNNING)) << name(point().mode);
  ASSERT_TRUE(wait_for([] { return point().step > 1000; }, 20.0)) << point().step;
  p = point();
  EXPECT_DOUBLE_EQ(p.pantographs.at(0).applied_force, hil_rostest::kSteadyForce);
  EXPECT_DOUBLE_EQ(p.speed, 15.0);
  r = trigger("arm");
  EXPECT_FALSE(r.success) << r.message;
  EXPECT_NE(r.message.find("running"), std::string::npos) << r.message;  // says why
  EXPECT_EQ(name(next_point().mode), "RUNNING");
  expect_refused(set_paused(false), point(), false, "set_paused false while running");

  // 3. Stamps: the wall clock (as the rig's), the simulation time in its own field. Received
  // within a second of being stamped (a generous bound for a loaded machine; the simulation time
  // started at 0, decades before the wall clock's epoch-based seconds).
  {
    const auto [last, last_wall] = heard->points.last_with_arrival();
    EXPECT_LT(std::fabs((last_wall - ros::WallTime(last.header.stamp.sec, last.header.stamp.nsec)).toSec()), 1.0);
    EXPECT_NEAR(last.simulation_time, static_cast<double>(last.step) * last.dt, 1e-6);
  }

  // 4. cmd/train_speed while running: the train slows to 10 m/s at 20 m/s^2; 200 m/s is rejected with the pass
  // node's message and changes nothing.
  v.data = 10.0;
  speed_pub.publish(v);
  ASSERT_TRUE(wait_for([] { return point().speed == 10.0; }, 20.0)) << point().speed;
  v.data = 200.0;
  speed_pub.publish(v);
  ASSERT_TRUE(wait_for([] {
    return heard->errors.has({"cmd/train_speed = 200 m/s rejected: allowed 0 to below "});
  }, 10.0)) << "no rejection logged";
  ros::WallDuration(0.5).sleep();
  EXPECT_EQ(next_point().speed, 10.0);

  // 5. ~set_paused true: the line is held (step and simulation time stand, the point does not
  // move) while the contact points go on with wall-clock stamps.
  std_srvs::SetBool::Response pr = set_paused(true);
  EXPECT_TRUE(pr.success) << pr.message;
  ASSERT_TRUE(mode_is(ContactPointArray::PAUSED)) << name(point().mode);
  const ContactPointArray paused = next_point();
  ros::WallDuration(1.0).sleep();
  p = next_point();
  EXPECT_EQ(name(p.mode), "PAUSED");
  EXPECT_EQ(p.step, paused.step) << "stepped while paused";
  EXPECT_EQ(p.simulation_time, paused.simulation_time);
  EXPECT_EQ(p.pantographs.at(0).position, paused.pantographs.at(0).position);
  EXPECT_EQ(p.pantographs.at(0).height, paused.pantographs.at(0).height);
  EXPECT_EQ(p.pantographs.at(0).velocity, 0.0);
  EXPECT_EQ(p.pantographs.at(0).path_velocity, 0.0);
  // (slept 1 s: the stamps moved on by most of it whatever the load)
  EXPECT_GT((p.header.stamp - paused.header.stamp).toSec(), 0.5) << "contact points not stamped in wall time";
  expect_refused(set_paused(true), p, true, "set_paused true while paused");
  expect_refused(trigger("arm"), p, true, "arm while paused");
  pr = set_paused(false);
  EXPECT_TRUE(pr.success) << pr.message;
  ASSERT_TRUE(mode_is(ContactPointArray::RUNNING)) << name(point().mode);
  ASSERT_TRUE(wait_for([&] { return point().step > paused.step + 500; }, 20.0)) << "not stepping after resuming";

  // 6. ~reset: a new pass from the start, pass_count + 1, time running on, the commanded speed kept.
  const ContactPointArray before_reset = next_point();
  ASSERT_GT(before_reset.pantographs.at(0).position, 0.0);
  r = trigger("reset");
  EXPECT_TRUE(r.success) << r.message;
  ASSERT_TRUE(wait_for([&] { return point().pass_count == before_reset.pass_count + 1; }, 10.0));
  p = point();
  EXPECT_EQ(name(p.mode), "RUNNING");
  EXPECT_GE(p.step, before_reset.step) << "time rewound";
  EXPECT_GE(p.simulation_time, before_reset.simulation_time) << "time rewound";
  // (the train moved on at 10 m/s for a few steps at most since the reset; before it, it was a
  // few metres further on at least: 0.5 s of running at 10 m/s and more)
  EXPECT_LT(p.pantographs.at(0).position, before_reset.pantographs.at(0).position);
  EXPECT_EQ(p.speed, 10.0);

  // 7. ~stop, after a second of running (the line moves): the safe hold (the train stops), then
  // ENDED once the line has settled, the statistics of the stopped pass written. Then every call
  // but ~arm is refused.
  ASSERT_TRUE(wait_for([&] { return point().step > p.step + 2000; }, 30.0)) << "not stepping after the reset";
  r = trigger("stop");
  EXPECT_TRUE(r.success) << r.message;
  ASSERT_TRUE(mode_is(ContactPointArray::SAFE_HOLD, 5.0)) << name(point().mode);
  r = trigger("stop");
  EXPECT_FALSE(r.success) << r.message;
  ASSERT_TRUE(mode_is(ContactPointArray::ENDED, 60.0)) << name(point().mode);
  const ContactPointArray ended = next_point();
  EXPECT_EQ(ended.speed, 0.0);
  EXPECT_DOUBLE_EQ(ended.pantographs.at(0).applied_force, 100.0) << "not ramped to the static uplift";
  ASSERT_TRUE(wait_for([&] { return std::ifstream(stats_file).good(); }, 10.0)) << "no " << stats_file;
  ros::WallDuration(0.2).sleep();  // (written atomically; the wait is for the worker thread)
  {
    std::ifstream in(stats_file);
    std::stringstream text;
    text << in.rdbuf();
    const nlohmann::json j = nlohmann::json::parse(text.str());
    EXPECT_EQ(j.at("speed_kmh").get<double>(), 0.0);
    EXPECT_NEAR(j.at("simulated_time_s").get<double>(), ended.simulation_time, 1e-9);
  }
  expect_refused(trigger("stop"), ended, true, "stop after the end");
  expect_refused(trigger("reset"), ended, true, "reset after the end");
  expect_refused(set_paused(true), ended, true, "set_paused after the end");
  ros::WallDuration(0.5).sleep();
  EXPECT_EQ(next_point().step, ended.step) << "stepped after the end";

  // 8. ~arm after the end: a new pass without a relaunch, at the commanded speed, started by the
  // rig's measurements (still coming).
  r = trigger("arm");
  EXPECT_TRUE(r.success) << r.message;
  ASSERT_TRUE(wait_for([&] { return point().pass_count == ended.pass_count + 1; }, 10.0));
  ASSERT_TRUE(mode_is(ContactPointArray::RUNNING)) << name(point().mode);
  ASSERT_TRUE(wait_for([&] { return point().step > ended.step + 500; }, 20.0)) << "the new pass does not step";
  p = point();
  EXPECT_EQ(p.speed, 10.0);
  EXPECT_LT(p.pantographs.at(0).position, ended.pantographs.at(0).position);
  EXPECT_DOUBLE_EQ(p.pantographs.at(0).applied_force, hil_rostest::kSteadyForce);
  EXPECT_TRUE(ros_layer::all_finite(p));
  std::remove(stats_file.c_str());
}

int main(int argc, char** argv) {
  ros_test::init(argc, argv, "test_hil_services");
  Heard h;
  heard = &h;
  hil_rostest::heard_points = &h;
  return hil_rostest::run_with_rig<MeasuredContactForce>("hil/contact_force", hil_rostest::measure_steady);
}
