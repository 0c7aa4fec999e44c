// The rig of the hardware-in-the-loop rostests (test_hil_outputs, test_hil_safety,
// test_hil_services, test_hil_viewer): catenary_sim_hil_node runs at 1 kHz without hardware and the test measures
// for it, on a thread of its own, while the test's checks run against what the node publishes.
#pragma once

#include <gtest/gtest.h>
#include <ros/ros.h>

#include <atomic>
#include <functional>
#include <string>
#include <thread>
#include <utility>

#include "catenary_sim/ContactPointArray.h"
#include "catenary_sim/MeasuredContactForce.h"
#include "ros_test_support.hpp"

namespace hil_rostest {

// Polls every 5 ms of wall time (a few of the node's periods).
inline bool wait_for(const std::function<bool()>& cond, double timeout_s) {
  return ros_test::wait_for(cond, timeout_s, 0.005);
}

// Publishes on `topic`, once a millisecond of wall time (the node's 1 kHz), the measurement that
// `measure` fills, stamped with the wall clock as a rig's own clock would; `measure` returns false
// where the rig stays silent for that millisecond. Stops when destroyed.
template <class M>
class Rig {
 public:
  Rig(const std::string& topic, std::function<bool(M&)> measure)
      : thread_([this, topic, measure = std::move(measure)] { send(topic, measure); }) {}
  Rig(const Rig&) = delete;
  Rig& operator=(const Rig&) = delete;
  ~Rig() {
    quit_ = true;
    thread_.join();
  }

 private:
  void send(const std::string& topic, const std::function<bool(M&)>& measure) {
    ros::NodeHandle nh;
    ros::Publisher pub = nh.advertise<M>(topic, 10);
    ros::WallTime next = ros::WallTime::now();
    while (!quit_ && ros::ok()) {
      next += ros::WallDuration(0.001);
      ros::WallTime::sleepUntil(next);
      M m;
      if (!measure(m)) continue;
      m.header.stamp = ros::Time::now();
      pub.publish(m);
    }
  }

  std::atomic<bool> quit_{false};
  std::thread thread_;  // (last: started once quit_ is set up)
};

// A rig that measures kSteadyForce all along, above the static uplift (100 N) of the scenes of
// these tests, so that a running pass is told from a held one.
constexpr double kSteadyForce = 120.0;  // N
inline bool measure_steady(catenary_sim::MeasuredContactForce& m) {
  m.force = {kSteadyForce};
  return true;
}

// What a test hears of the node: its contact points (made in main, after ros::init).
struct HeardPoints {
  ros::NodeHandle nh;  // (first: the end of the last handle would shut ROS down)
  ros_test::Recorder<catenary_sim::ContactPointArray> points{"hil/contact_point", 100,
                                                             ros::TransportHints().tcpNoDelay()};
};
// The HeardPoints of the test (set in main), and its newest contact point.
inline HeardPoints* heard_points = nullptr;
inline catenary_sim::ContactPointArray point() { return heard_points->points.last(); }

// RUN_ALL_TESTS with the test's subscriptions served by two spinner threads and the rig
// measuring on `topic`; then the rig stops and ROS shuts down.
template <class M>
int run_with_rig(const std::string& topic, std::function<bool(M&)> measure) {
  return ros_test::run_all_tests(2, [&] {
    Rig<M> rig(topic, std::move(measure));
    return RUN_ALL_TESTS();
  });
}

}  // namespace hil_rostest
