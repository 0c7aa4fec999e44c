// rostest companion of hil_outputs.test: catenary_sim_hil_node at 1 kHz without a rig; this test is
// a rig whose load cell sends geometry_msgs/WrenchStamped on hil/contact_wrench (force.z: the
// force of the pantograph on the wire, z up). It checks that valid wrenches drive the loop, that a
// NaN (or infinite) component is rejected with an error naming the field, the value and what is
// allowed, leaving the measurement in effect as it was, and that pantograph_state and wire_shape
// come decimated (publish_rate 50 Hz, shape_rate 5 Hz), with increasing simulation-time stamps and
// finite, sane values.
#include <geometry_msgs/WrenchStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

#include "catenary_sim/ContactPointArray.h"
#include "catenary_sim/PantographStateArray.h"
#include "catenary_sim/WireShapeArray.h"
#include "catenary_sim/ros/hil.hpp"
#include "hil_rig.hpp"
#include "ros_test_support.hpp"

using namespace catenary_sim;

namespace {

using hil_rostest::wait_for;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kWireHeight = 5.3;  // m, contact_wire_height of the reference line

// What the test hears of the node (made in main, after ros::init).
struct Heard {
  ros::NodeHandle nh;  // (first: the end of the last handle would shut ROS down)
  ros_test::Recorder<ContactPointArray> points{"hil/contact_point", 100000, ros::TransportHints().tcpNoDelay()};
  ros_test::Recorder<PantographStateArray> states{"pantograph_state", 1000};
  ros_test::Recorder<WireShapeArray> shapes{"wire_shape", 100};
  ros_test::NodeLog errors{"catenary_sim_hil"};  // the node's ERROR log lines
};
Heard* heard = nullptr;

// The rig: sends the wrench `value` while `sending`.
std::atomic<bool> sending{false};
std::mutex values_mu;
geometry_msgs::Wrench value;

bool measure(geometry_msgs::WrenchStamped& m) {
  if (!sending) return false;
  m.header.frame_id = "load_cell";
  std::lock_guard<std::mutex> l(values_mu);
  m.wrench = value;
  return true;
}

void send(double fz, double tx = 0.0) {
  std::lock_guard<std::mutex> l(values_mu);
  value = geometry_msgs::Wrench();
  value.force.x = 3.0;  // (ignored: only force.z is the contact force)
  value.force.z = fz;
  value.torque.x = tx;
}

ContactPointArray last_point() { return heard->points.last(); }

bool logged(const std::vector<std::string>& parts) { return heard->errors.has(parts); }

}  // namespace

TEST(HilOutputs, WrenchInputPantographStateAndWireShape) {
  ASSERT_TRUE(wait_for([] { return last_point().header.stamp != ros::Time(); }, 20.0)) << "no hil/contact_point";
  EXPECT_EQ(last_point().mode, ContactPointArray::WAITING);

  // 1. Valid wrenches (force.z 120 N) start and drive the loop.
  send(120.0);
  sending = true;
  ASSERT_TRUE(wait_for([] { return last_point().mode == ContactPointArray::RUNNING; }, 2.0));
  ros::WallDuration(1.0).sleep();
  const ContactPointArray r = last_point();
  EXPECT_EQ(r.mode, ContactPointArray::RUNNING);
  EXPECT_DOUBLE_EQ(r.pantographs[0].applied_force, 120.0);
  EXPECT_GE(r.pantographs[0].measurement_age, 0.0);
  EXPECT_LT(r.pantographs[0].measurement_age, 0.05);

  // 2. NaN force.z for 30 ms (well below ~hil/timeout, 0.2 s here): rejected, 120 N stays in effect, still running.
  send(kNaN);
  ros::WallDuration(0.03).sleep();
  send(120.0);
  ros::WallDuration(0.05).sleep();
  EXPECT_TRUE(logged({"hil/contact_wrench.wrench.force.z", "nan", "rejected", "allowed"}))
      << "no error naming the field, the value and the allowed range";
  // 3. An infinite torque: rejected naming that field (after the 1 s throttle of the error log).
  ros::WallDuration(1.1).sleep();
  send(105.0, std::numeric_limits<double>::infinity());
  ros::WallDuration(0.03).sleep();
  send(120.0);
  ros::WallDuration(0.05).sleep();
  EXPECT_TRUE(logged({"hil/contact_wrench.wrench.torque.x", "inf", "rejected", "finite"}));
  // 4. Interleaved NaN and 110 N wrenches: only 120 or 110 N ever applied.
  for (int i = 0; i < 10; ++i) {
    send(kNaN);
    ros::WallDuration(0.01).sleep();
    send(110.0);
    ros::WallDuration(0.01).sleep();
  }
  ros::WallDuration(0.05).sleep();
  sending = false;
  EXPECT_DOUBLE_EQ(last_point().pantographs[0].applied_force, 110.0);
  for (const ContactPointArray& p : heard->points.take()) {
    ASSERT_TRUE(ros_layer::all_finite(p)) << "step " << p.step;
    if (p.step <= r.step) continue;
    EXPECT_EQ(p.mode, ContactPointArray::RUNNING) << "step " << p.step << ": a rejected wrench stopped the input";
    const double f = p.pantographs[0].applied_force;
    EXPECT_TRUE(f == 120.0 || f == 110.0) << "step " << p.step << ": " << f;
  }

  // 5. pantograph_state and wire_shape: decimated, increasing stamps, finite and sane.
  const auto [states, state_wall] = heard->states.take_with_arrivals();
  const auto [shapes, shape_wall] = heard->shapes.take_with_arrivals();
  ASSERT_GT(states.size(), 20u);
  ASSERT_GT(shapes.size(), 3u);
  const double state_s = (state_wall.back() - state_wall.front()).toSec();
  const double shape_s = (shape_wall.back() - shape_wall.front()).toSec();
  EXPECT_LT((states.size() - 1) / state_s, 60.0) << "pantograph_state above ~publish_rate";
  EXPECT_LT((shapes.size() - 1) / shape_s, 6.0) << "wire_shape above ~shape_rate";
  for (std::size_t i = 0; i < states.size(); ++i) {
    const PantographStateArray& s = states[i];
    if (i > 0) {
      EXPECT_GE(s.header.stamp, states[i - 1].header.stamp);
    }
    ASSERT_EQ(s.pantographs.size(), 1u);
    const PantographState& p = s.pantographs[0];
    EXPECT_TRUE(std::isfinite(p.position) && std::isfinite(p.head_height) && std::isfinite(p.speed)) << i;
    EXPECT_NEAR(p.head_height, kWireHeight, 0.2) << "the head height of an external pantograph is the contact point's";
    EXPECT_TRUE(p.displacement.empty());
    EXPECT_GE(p.speed, 0.0);
    EXPECT_LE(p.speed, 100.0 / 3.6 + 1e-9);
    if (i > 0) {
      EXPECT_GE(p.position, states[i - 1].pantographs[0].position);
    }
  }
  EXPECT_GT(states.back().header.stamp, states.front().header.stamp);
  EXPECT_GT(states.back().pantographs[0].position, states.front().pantographs[0].position) << "the train moved";
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    const WireShapeArray& s = shapes[i];
    if (i > 0) {
      EXPECT_GT(s.header.stamp, shapes[i - 1].header.stamp);
    }
    ASSERT_GE(s.wires.size(), 2u);
    for (const WireShape& w : s.wires) {
      ASSERT_EQ(w.stations.size(), w.heights.size());
      ASSERT_GT(w.stations.size(), 10u);
      for (std::size_t k = 0; k < w.heights.size(); ++k) {
        EXPECT_TRUE(std::isfinite(w.heights[k]));
        EXPECT_GT(w.heights[k], 4.5) << w.name;
        EXPECT_LT(w.heights[k], 7.5) << w.name;
        if (k > 0) {
          EXPECT_GT(w.stations[k], w.stations[k - 1]);
        }
      }
    }
  }
}

int main(int argc, char** argv) {
  ros_test::init(argc, argv, "test_hil_outputs");
  Heard h;
  heard = &h;
  return hil_rostest::run_with_rig<geometry_msgs::WrenchStamped>("hil/contact_wrench", measure);
}
