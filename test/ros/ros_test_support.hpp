// Helpers of the rostest companions (test/ros): a topic recorder, a recorder of a node's log lines,
// a wall-clock wait and the companions' main().
#pragma once

#include <gtest/gtest.h>
#include <ros/ros.h>
#include <ros/topic.h>
#include <rosgraph_msgs/Log.h>
#include <std_msgs/String.h>

#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace ros_test {

// Collects the messages of one topic (relative names resolve in the test's namespace), each with
// the wall time it arrived at.
template <class M>
struct Recorder {
  explicit Recorder(const std::string& topic, std::uint32_t queue = 100,
                    const ros::TransportHints& hints = ros::TransportHints()) {
    sub = ros::NodeHandle().subscribe<M>(
        topic, queue,
        [this](const typename M::ConstPtr& m) {
          const ros::WallTime now = ros::WallTime::now();
          std::lock_guard<std::mutex> l(mu);
          msgs.push_back(*m);
          arrivals.push_back(now);
        },
        ros::VoidConstPtr(), hints);
  }
  std::vector<M> take() {
    std::lock_guard<std::mutex> l(mu);
    return msgs;
  }
  // The messages and their arrival times, taken together (the same length).
  std::pair<std::vector<M>, std::vector<ros::WallTime>> take_with_arrivals() {
    std::lock_guard<std::mutex> l(mu);
    return {msgs, arrivals};
  }
  // The newest message (a default one before the first).
  M last() { return last_with_arrival().first; }
  // The newest message and when it arrived (a default message at time 0 before the first).
  std::pair<M, ros::WallTime> last_with_arrival() {
    std::lock_guard<std::mutex> l(mu);
    if (msgs.empty()) return {M(), ros::WallTime()};
    return {msgs.back(), arrivals.back()};
  }
  void clear() {
    std::lock_guard<std::mutex> l(mu);
    msgs.clear();
    arrivals.clear();
  }
  std::size_t size() {
    std::lock_guard<std::mutex> l(mu);
    return msgs.size();
  }
  // The subscription ends before the lists it writes into: a message arriving on the spinner's
  // thread while a test's recorder goes out of scope must not write into freed memory (roscpp's
  // shutdown waits for a callback that is running).
  ~Recorder() { sub.shutdown(); }
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;
  ros::Subscriber sub;
  std::mutex mu;
  std::vector<M> msgs;
  std::vector<ros::WallTime> arrivals;
};

// The lines on /rosout of the nodes whose name contains `node`, at `min_level` or above.
struct NodeLog {
  explicit NodeLog(const std::string& node, std::uint8_t min_level = rosgraph_msgs::Log::ERROR) {
    sub = ros::NodeHandle().subscribe<rosgraph_msgs::Log>(
        "/rosout", 1000, [this, node, min_level](const rosgraph_msgs::Log::ConstPtr& m) {
          if (m->name.find(node) != std::string::npos && m->level >= min_level) {
            std::lock_guard<std::mutex> l(mu);
            lines.push_back(m->msg);
          }
        },
        ros::VoidConstPtr());
  }
  // Whether one line holds every one of `parts`.
  bool has(const std::vector<std::string>& parts) {
    std::lock_guard<std::mutex> l(mu);
    for (const std::string& line : lines) {
      bool all = true;
      for (const std::string& p : parts) all = all && line.find(p) != std::string::npos;
      if (all) return true;
    }
    return false;
  }
  // How many lines hold `part`.
  int count(const std::string& part) {
    std::lock_guard<std::mutex> l(mu);
    int n = 0;
    for (const std::string& line : lines) n += line.find(part) != std::string::npos ? 1 : 0;
    return n;
  }
  ~NodeLog() { sub.shutdown(); }  // as Recorder's
  NodeLog(const NodeLog&) = delete;
  NodeLog& operator=(const NodeLog&) = delete;
  ros::Subscriber sub;
  std::mutex mu;
  std::vector<std::string> lines;
};

// The pass node's latched pass_status ("(none)" if nothing came within 5 s).
inline std::string pass_status() {
  const auto m = ros::topic::waitForMessage<std_msgs::String>("pass_status", ros::Duration(5.0));
  return m ? m->data : "(none)";
}

// Polls `cond` every `poll_s` of wall time until it holds or `timeout_s` has passed.
inline bool wait_for(const std::function<bool()>& cond, double timeout_s, double poll_s = 0.01) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout_s);
  while (ros::ok() && ros::WallTime::now() < end) {
    if (cond()) return true;
    ros::WallDuration(poll_s).sleep();
  }
  return cond();
}

// gtest and ROS initialised, this process the node `node`: the head of a companion's main().
inline void init(int& argc, char** argv, const std::string& node) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, node);
}

// `run` (all the tests by default) with the subscriptions served by `spinner_threads` threads,
// then ROS shut down: the tail of a companion's main().
inline int run_all_tests(int spinner_threads, const std::function<int()>& run = [] { return RUN_ALL_TESTS(); }) {
  ros::AsyncSpinner spinner(spinner_threads);
  spinner.start();
  const int rc = run();
  spinner.stop();
  ros::shutdown();
  return rc;
}

// The whole main() of a companion whose subscriptions are the tests' own.
inline int ros_test_main(int argc, char** argv, const std::string& node, int spinner_threads = 2) {
  init(argc, argv, node);
  ros::NodeHandle nh;  // keeps the node up between the tests' own handles
  return run_all_tests(spinner_threads);
}

}  // namespace ros_test
