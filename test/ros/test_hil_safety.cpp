// rostest companion of hil_safety.test: catenary_sim_hil_node at 1 kHz without a rig; this test is
// the rig. It checks the waiting state, running on measurements, the safe hold when they stop
// (train stopping, force ramped to the static uplift, an ERROR diagnostic), that NaN, infinite,
// out-of-range and wrongly sized measurements are rejected (they do not end the safe hold, the
// error is logged at most about once a second) and that the node never publishes NaN.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <vector>

#include "catenary_sim/ContactForceArray.h"
#include "catenary_sim/ContactPointArray.h"
#include "catenary_sim/MeasuredContactForce.h"
#include "catenary_sim/ros/hil.hpp"
#include "hil_rig.hpp"
#include "ros_test_support.hpp"

using namespace catenary_sim;

namespace {

using hil_rostest::wait_for;

constexpr double kStatic = 100.0;  // N, static_uplift of reference_55m_hil.yaml

// What the test hears of the node (made in main, after ros::init).
struct Heard {
  ros::NodeHandle nh;  // (first: the end of the last handle would shut ROS down)
  ros_test::Recorder<ContactPointArray> points{"hil/contact_point", 100000, ros::TransportHints().tcpNoDelay()};
  ros_test::Recorder<ContactForceArray> forces{"contact_force", 1000};
  ros_test::NodeLog log{"catenary_sim_hil", rosgraph_msgs::Log::DEBUG};  // every line of the node
};
Heard* heard = nullptr;

// The node's diagnostics statuses, each with the wall time it arrived at.
std::mutex mu;
std::vector<diagnostic_msgs::DiagnosticStatus> diags;
std::vector<ros::WallTime> diag_wall;

int rejected_logs() { return heard->log.count("rejected"); }

// The rig: sends `values` while `sending`.
std::atomic<bool> sending{false};
std::mutex values_mu;
std::vector<double> values{kStatic};

bool measure(MeasuredContactForce& m) {
  if (!sending) return false;
  std::lock_guard<std::mutex> l(values_mu);
  m.force = values;
  return true;
}

void send(std::vector<double> v) {
  std::lock_guard<std::mutex> l(values_mu);
  values = std::move(v);
}

ContactPointArray last_point() { return heard->points.last(); }

// The newest diagnostics status of the node received after `since`.
bool diag_after(const ros::WallTime& since, diagnostic_msgs::DiagnosticStatus* out) {
  std::lock_guard<std::mutex> l(mu);
  for (std::size_t i = diags.size(); i-- > 0;)
    if (diag_wall[i] > since) {
      *out = diags[i];
      return true;
    }
  return false;
}

std::string value_of(const diagnostic_msgs::DiagnosticStatus& s, const std::string& key) {
  for (const auto& kv : s.values)
    if (kv.key == key) return kv.value;
  return "";
}

}  // namespace

TEST(HilSafety, WaitingRunningSafeHoldRejectionAndRecovery) {
  // 1. Waiting: no measurement, the line holds its initial state.
  ASSERT_TRUE(wait_for([] { return last_point().header.stamp != ros::Time(); }, 20.0)) << "no hil/contact_point";
  const ContactPointArray w0 = last_point();
  EXPECT_EQ(w0.mode, ContactPointArray::WAITING);
  EXPECT_EQ(w0.steps_per_period, 2u);
  EXPECT_DOUBLE_EQ(w0.dt, 0.0005);
  ASSERT_EQ(w0.pantographs.size(), 1u);
  EXPECT_NEAR(w0.pantographs[0].applied_force, kStatic, 1e-9);
  EXPECT_DOUBLE_EQ(w0.pantographs[0].measurement_age, -1.0);
  ros::WallDuration(0.3).sleep();
  EXPECT_EQ(last_point().step, w0.step) << "stepped without a measurement";
  diagnostic_msgs::DiagnosticStatus d;
  ASSERT_TRUE(wait_for([&] { return diag_after(ros::WallTime::now() - ros::WallDuration(0.3), &d); }, 5.0));
  EXPECT_EQ(d.level, diagnostic_msgs::DiagnosticStatus::WARN) << d.message;

  // 2. Running on 120 N measurements at 1 kHz.
  send({120.0});
  sending = true;
  ASSERT_TRUE(wait_for([] { return last_point().mode == ContactPointArray::RUNNING; }, 2.0));
  ros::WallDuration(1.0).sleep();
  ContactPointArray r = last_point();
  EXPECT_EQ(r.mode, ContactPointArray::RUNNING);
  EXPECT_GT(r.step, w0.step + 1000);
  EXPECT_NEAR(r.speed, 100.0 / 3.6, 1e-9);
  EXPECT_DOUBLE_EQ(r.pantographs[0].applied_force, 120.0);
  EXPECT_GE(r.pantographs[0].measurement_age, 0.0);
  EXPECT_LT(r.pantographs[0].measurement_age, 0.05);
  ASSERT_TRUE(wait_for([&] { return diag_after(ros::WallTime::now() - ros::WallDuration(0.05), &d); }, 2.0));
  EXPECT_EQ(d.level, diagnostic_msgs::DiagnosticStatus::OK) << d.message;

  // 3. The rig falls silent: after ~hil/timeout (0.05 s) the safe hold; ERROR diagnostic.
  sending = false;
  const ros::WallTime silent = ros::WallTime::now();
  ASSERT_TRUE(wait_for([] { return last_point().mode == ContactPointArray::SAFE_HOLD; }, 1.0));
  const double to_hold = (ros::WallTime::now() - silent).toSec();
  EXPECT_GT(to_hold, 0.045);
  EXPECT_LT(to_hold, 0.5);
  ASSERT_TRUE(wait_for([&] { return diag_after(silent + ros::WallDuration(0.1), &d) && d.level > 0; }, 3.0));
  EXPECT_EQ(d.level, diagnostic_msgs::DiagnosticStatus::ERROR) << d.message;
  EXPECT_NE(d.message.find("SAFE HOLD"), std::string::npos) << d.message;
  EXPECT_EQ(value_of(d, "mode"), "safe hold");
  // Deceleration 20 m/s^2 from 27.8 m/s: stopped within 1.4 s; force ramped (0.3 s) to the static uplift.
  ASSERT_TRUE(wait_for([] { return last_point().speed == 0.0; }, 3.0)) << last_point().speed;
  const ContactPointArray h1 = last_point();
  ros::WallDuration(0.3).sleep();
  const ContactPointArray h2 = last_point();
  EXPECT_EQ(h2.mode, ContactPointArray::SAFE_HOLD);
  EXPECT_GT(h2.step, h1.step) << "the line is still integrated in the safe hold";
  EXPECT_DOUBLE_EQ(h2.pantographs[0].position, h1.pantographs[0].position) << "the train moves in the safe hold";
  EXPECT_DOUBLE_EQ(h2.pantographs[0].applied_force, kStatic);
  EXPECT_GT(h2.pantographs[0].measurement_age, 1.0);
  // The ramp: from 120 N down to 100 N, never outside.
  {
    bool ramped = false;
    for (const ContactPointArray& p : heard->points.take())
      if (p.mode == ContactPointArray::SAFE_HOLD) {
        const double f = p.pantographs[0].applied_force;
        EXPECT_GE(f, kStatic - 1e-9);
        EXPECT_LE(f, 120.0 + 1e-9);
        ramped = ramped || (f > 101.0 && f < 119.0);
      }
    EXPECT_TRUE(ramped) << "no intermediate force of the ramp seen";
  }

  // 4. Bad measurements do not end the safe hold, change nothing and are logged throttled.
  const int logs_before = rejected_logs();
  const ros::WallTime bad_start = ros::WallTime::now();
  for (const std::vector<double>& bad : std::vector<std::vector<double>>{
           {std::numeric_limits<double>::quiet_NaN()}, {std::numeric_limits<double>::infinity()}, {-100.0}, {5000.0},
           {100.0, 100.0}, {}}) {
    send(bad);
    sending = true;
    ros::WallDuration(0.25).sleep();  // 250 measurements each
  }
  sending = false;
  const double bad_s = (ros::WallTime::now() - bad_start).toSec();
  ros::WallDuration(0.1).sleep();
  const ContactPointArray b = last_point();
  EXPECT_EQ(b.mode, ContactPointArray::SAFE_HOLD);
  EXPECT_DOUBLE_EQ(b.pantographs[0].applied_force, kStatic);
  const ros::WallTime after_bad = ros::WallTime::now();
  ASSERT_TRUE(wait_for([&] { return diag_after(after_bad, &d); }, 2.0));
  EXPECT_EQ(d.level, diagnostic_msgs::DiagnosticStatus::ERROR) << d.message;
  EXPECT_GE(std::stoll(value_of(d, "measurements rejected")), 1000) << value_of(d, "measurements rejected");
  const int logs = rejected_logs() - logs_before;
  EXPECT_GE(logs, 1);
  EXPECT_LE(logs, static_cast<int>(bad_s) + 3) << "rejections not throttled: " << logs << " in " << bad_s << " s";

  // 5. Fresh valid measurements end the safe hold; the train accelerates back.
  send({110.0});
  sending = true;
  const ros::WallTime resumed = ros::WallTime::now();
  ASSERT_TRUE(wait_for([] { return last_point().mode == ContactPointArray::RUNNING; }, 1.0));
  EXPECT_LT((ros::WallTime::now() - resumed).toSec(), 0.2);
  ros::WallDuration(0.5).sleep();
  r = last_point();
  EXPECT_GT(r.speed, 5.0);  // 20 m/s^2 for 0.5 s
  EXPECT_DOUBLE_EQ(r.pantographs[0].applied_force, 110.0);
  const ros::WallTime after_resume = ros::WallTime::now();
  ASSERT_TRUE(wait_for([&] { return diag_after(after_resume, &d); }, 2.0));
  EXPECT_NE(d.level, diagnostic_msgs::DiagnosticStatus::ERROR) << d.message;

  // 6. NaN between valid measurements while running: rejected, the valid value stays in effect.
  for (int i = 0; i < 20; ++i) {
    send({std::numeric_limits<double>::quiet_NaN()});
    ros::WallDuration(0.01).sleep();
    send({105.0});
    ros::WallDuration(0.01).sleep();
  }
  sending = false;
  ros::WallDuration(0.02).sleep();

  // Never a NaN (or inf) in anything the node published.
  const std::vector<ContactPointArray> points = heard->points.take();
  const std::vector<ContactForceArray> forces = heard->forces.take();
  EXPECT_GT(points.size(), 3000u);
  for (const ContactPointArray& p : points) {
    ASSERT_TRUE(ros_layer::all_finite(p)) << "step " << p.step;
    if (p.mode == ContactPointArray::RUNNING && p.step > r.step) {
      const double f = p.pantographs[0].applied_force;
      EXPECT_TRUE(f == 110.0 || f == 105.0) << f;
    }
  }
  EXPECT_GT(forces.size(), 50u);
  for (const ContactForceArray& f : forces)
    for (const ContactForce& c : f.pantographs) {
      EXPECT_TRUE(std::isfinite(c.position) && std::isfinite(c.total));
      for (double x : c.wire_forces) EXPECT_TRUE(std::isfinite(x));
    }
}

int main(int argc, char** argv) {
  ros_test::init(argc, argv, "test_hil_safety");
  Heard h;
  heard = &h;
  ros::Subscriber diag_sub = h.nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 100, [](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
        std::lock_guard<std::mutex> l(mu);
        for (const auto& s : m->status)
          if (s.name.find("hardware in the loop") != std::string::npos) {
            diags.push_back(s);
            diag_wall.push_back(ros::WallTime::now());
          }
      },
      ros::VoidConstPtr());
  return hil_rostest::run_with_rig<MeasuredContactForce>("hil/contact_force", measure);
}
