// Helpers of the rostest companions (test/ros): a topic recorder and a wall-clock wait.
#pragma once

#include <ros/ros.h>

#include <functional>
#include <mutex>
#include <string>
#include <vector>

namespace ros_test {

// Collects the messages of one topic (relative names resolve in the test's namespace).
template <class M>
struct Recorder {
  explicit Recorder(const std::string& topic, std::uint32_t queue = 100) {
    sub = ros::NodeHandle().subscribe<M>(topic, queue, [this](const typename M::ConstPtr& m) {
      std::lock_guard<std::mutex> l(mu);
      msgs.push_back(*m);
    });
  }
  std::vector<M> take() {
    std::lock_guard<std::mutex> l(mu);
    return msgs;
  }
  void clear() {
    std::lock_guard<std::mutex> l(mu);
    msgs.clear();
  }
  std::size_t size() {
    std::lock_guard<std::mutex> l(mu);
    return msgs.size();
  }
  ros::Subscriber sub;
  std::mutex mu;
  std::vector<M> msgs;
};

// Polls `cond` every `poll_s` of wall time until it holds or `timeout_s` has passed.
inline bool wait_for(const std::function<bool()>& cond, double timeout_s, double poll_s = 0.01) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout_s);
  while (ros::ok() && ros::WallTime::now() < end) {
    if (cond()) return true;
    ros::WallDuration(poll_s).sleep();
  }
  return cond();
}

}  // namespace ros_test
