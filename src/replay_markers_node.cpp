// replay_markers: the rviz markers of a recorded pass. A bag recorded with pass.launch record:=true
// (or written by simulate_pass --bag) has no markers; played back (launch/replay.launch), this node
// rebuilds them from the recorded wire_shape, pantograph_state and contact_force with the live
// node's own to_markers() (state_from_messages: no physics here). The constant geometry (masts,
// steady arms, droppers) comes from the scene the recording carries (the node's latched
// /catenary_sim/scene_yaml, recorded with the pass), or from ~scene when given.
//
// Parameters: ~scene (optional: a scene YAML file, which then must be the scene of the recording:
// checked against the one the recording carries, scene_difference),
// ~scene_topic (/catenary_sim/scene_yaml), ~vertical_scale (10, as the live default),
// ~shape_resolution (1 m between line-strip points, 0: every node), ~publish_view_frame (true:
// send line -> train_view with each marker message, as the live node does, unless the bag has it
// already). Markers are drawn for every recorded wire_shape (the live node's ~shape_rate, 10 Hz),
// with the pantograph_state and contact_force of the same stamp.
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <deque>
#include <memory>
#include <stdexcept>
#include <string>

#include "catenary_sim/ContactForceArray.h"
#include "catenary_sim/PantographStateArray.h"
#include "catenary_sim/WireShapeArray.h"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/scene/scene.hpp"
#include "catenary_sim/ros/conversions.hpp"
#include "catenary_sim/ros/markers.hpp"
#include "catenary_sim/ros/params.hpp"
#include "catenary_sim/ros/replay.hpp"

using namespace catenary_sim;
using namespace catenary_sim::ros_layer;

namespace {

double number_param(const ros::NodeHandle& pnh, const char* name, double fallback, double lo, double hi,
                    const char* unit) {
  double v = fallback;
  int i = 0;
  if (pnh.hasParam(name)) {
    if (pnh.getParam(name, v)) {
    } else if (pnh.getParam(name, i)) {
      v = i;
    } else {
      throw std::runtime_error(std::string("parameter ~") + name + " must be a number");
    }
  }
  if (!std::isfinite(v) || v < lo || v > hi)
    throw std::runtime_error(std::string("parameter ~") + name + " = " + format_number(v) + " rejected: allowed " +
                             range_text(lo, hi, false, unit));
  return v;
}

class ReplayMarkers {
 public:
  ReplayMarkers(ros::NodeHandle nh, ros::NodeHandle pnh) {
    std::string scene, scene_topic = "/catenary_sim/scene_yaml";
    if (pnh.hasParam("scene") && !pnh.getParam("scene", scene))
      throw std::runtime_error("parameter ~scene must be a file path (empty: the recording's scene)");
    if (pnh.hasParam("scene_topic") && (!pnh.getParam("scene_topic", scene_topic) || scene_topic.empty()))
      throw std::runtime_error("parameter ~scene_topic must be a topic name");
    if (!scene.empty()) {
      try {
        use_scene(load_scene_file(scene));
      } catch (const SceneError& e) {
        throw std::runtime_error("parameter ~scene = '" + scene + "': " + e.what());
      }
      given_ = true;
    }
    // With ~scene, the recording's scene checks it: a line that differs only where the messages
    // do not show it would be drawn wrongly without a word.
    subs_.push_back(nh.subscribe(scene_topic, 1, &ReplayMarkers::on_scene, this));
    options_.vertical_scale = number_param(pnh, "vertical_scale", 10.0, 1e-9, 10000.0, "");
    options_.shape_resolution = number_param(pnh, "shape_resolution", 1.0, 0.0, 100.0, "m (0: every node)");
    pnh.param("publish_view_frame", view_, true);
    pub_ = nh.advertise<visualization_msgs::MarkerArray>("markers", 2);
    subs_.push_back(nh.subscribe("wire_shape", 20, &ReplayMarkers::on_shape, this));
    subs_.push_back(nh.subscribe("pantograph_state", 500, &ReplayMarkers::on_state, this));
    subs_.push_back(nh.subscribe("contact_force", 500, &ReplayMarkers::on_force, this));
    if (view_) subs_.push_back(nh.subscribe("/tf", 100, &ReplayMarkers::on_tf, this));
    ROS_INFO("replay_markers: scene %s; drawing %s from wire_shape, pantograph_state and contact_force",
             scene.empty() ? ("of the recording (" + scene_topic + ")").c_str() : scene.c_str(), pub_.getTopic().c_str());
  }

 private:
  // Buffers long enough for the state topics between two shapes (200 Hz x 0.1 s) with margin.
  static constexpr std::size_t kKeep = 400;

  template <class T>
  void keep(std::deque<T>& q, const T& m) {
    // rosbag play --loop (or a new bag) goes back in time: forget what came before.
    if (!q.empty() && m.header.stamp < q.back().header.stamp) reset();
    q.push_back(m);
    if (q.size() > kKeep) q.pop_front();
  }
  void reset() {
    shapes_.clear();
    states_.clear();
    forces_.clear();
    last_drawn_ = ros::Time();
  }

  void use_scene(const Scene& scene) {
    model_ = std::make_unique<Model>(build_model(scene));
    state_ = make_state(*model_);  // (on a 3-D line with its lateral state: wires drawn at their lateral positions)
    last_drawn_ = ros::Time();
    drawn_any_ = false;
  }

  // A new recording's scene: what the last one drew goes (markers have no lifetime, and parts of
  // a kind the new line lacks, its stitch wires or auxiliary, would stay drawn).
  void clear_drawing() {
    if (!pub_ || !drawn_any_) return;
    visualization_msgs::MarkerArray clear;
    clear.markers.emplace_back();
    clear.markers.back().action = visualization_msgs::Marker::DELETEALL;
    pub_.publish(clear);
  }

  void on_scene(const std_msgs::String::ConstPtr& m) {
    if (m->data == scene_text_) return;
    clear_drawing();
    scene_text_ = m->data;
    if (given_) {
      try {
        mismatch_ = scene_difference(*model_, build_model(scene_from_message(m->data)));
      } catch (const std::exception& e) {
        mismatch_.clear();
        ROS_WARN("replay_markers: the recording's scene cannot be read (%s): drawing with ~scene unchecked", e.what());
        return;
      }
      if (!mismatch_.empty())
        ROS_ERROR("replay_markers: ~scene is not the scene of the recording: %s; leave ~scene empty to draw with the "
                  "recording's own", mismatch_.c_str());
      drawn_any_ = false;
      return;
    }
    try {
      use_scene(scene_from_message(m->data));
      scene_error_.clear();
      ROS_INFO("replay_markers: scene %s from the recording", model_->scene.name.c_str());
    } catch (const std::exception& e) {
      model_.reset();  // (never drawn with the scene of an earlier recording)
      drawn_any_ = false;
      scene_error_ = e.what();
      ROS_ERROR("replay_markers: the recording's scene cannot be used: %s", e.what());
    }
  }

  void on_shape(const WireShapeArray::ConstPtr& m) { keep(shapes_, *m); draw(); }
  void on_state(const PantographStateArray::ConstPtr& m) { keep(states_, *m); draw(); }
  void on_force(const ContactForceArray::ConstPtr& m) { keep(forces_, *m); draw(); }

  void on_tf(const ros::MessageEvent<tf2_msgs::TFMessage const>& ev) {
    if (!view_ || ev.getPublisherName() == ros::this_node::getName()) return;
    for (const auto& t : ev.getMessage()->transforms)
      if (t.child_frame_id == view_frame_id()) {
        ROS_INFO("replay_markers: the recording has %s in /tf (%s): not sending it", view_frame_id().c_str(),
                 ev.getPublisherName().c_str());
        view_ = false;
        return;
      }
  }

  // The message of stamp t in q; else, once a later one has arrived (the exact one will not come:
  // each topic is in time order), the closest one before t; else null (wait).
  template <class T>
  static const T* match(const std::deque<T>& q, const ros::Time& t) {
    const T* before = nullptr;
    bool later = false;
    for (const T& m : q) {
      if (m.header.stamp == t) return &m;
      if (m.header.stamp < t) before = &m;
      else later = true;
    }
    return later ? before : nullptr;
  }

  void draw() {
    // The newest shape not drawn yet, with the state and force of its stamp.
    if (shapes_.empty()) return;
    if (!model_) {
      if (!scene_error_.empty())
        ROS_WARN_THROTTLE(10.0, "replay_markers: no scene to draw with: the recording's scene was refused (%s); give "
                          "a scene for it: replay.launch scene:=FILE", scene_error_.c_str());
      else
        ROS_WARN_THROTTLE(10.0, "replay_markers: no scene to draw with: the recording has no %s (recorded before the "
                          "node published it, or another recorder's topic list); give the scene of the recording: "
                          "replay.launch scene:=FILE", subs_.empty() ? "scene" : subs_[0].getTopic().c_str());
      return;
    }
    if (!mismatch_.empty()) return;  // (said once, when the recording's scene came)
    const WireShapeArray& shape = shapes_.back();
    const ros::Time t = shape.header.stamp;
    if (t == last_drawn_ && drawn_any_) return;
    const PantographStateArray* state = match(states_, t);
    const ContactForceArray* force = match(forces_, t);
    if (!state || !force) return;
    const std::string err = state_from_messages(*model_, shape, *state, *force, &state_);
    last_drawn_ = t;
    drawn_any_ = true;
    if (!err.empty()) {
      ROS_ERROR_THROTTLE(5.0, "replay_markers: cannot draw the recording: %s", err.c_str());
      return;
    }
    options_.frame = shape.header.frame_id.empty() ? "line" : shape.header.frame_id;
    // The transform first, so that rviz may know the line frame before the markers arrive.
    if (view_) tf_.sendTransform(to_view_transforms(*model_, state_, t, options_.frame));
    pub_.publish(to_markers(*model_, state_, t, options_));
  }

  std::unique_ptr<Model> model_;   // null until the scene is known
  std::string scene_text_;         // the recording's scene message last received
  std::string scene_error_;        // why it was refused ("" when in use)
  bool given_ = false;             // drawing with ~scene, checked against the recording's
  std::string mismatch_;           // how ~scene differs from the recording's scene ("" if it does not)
  State state_;
  MarkerOptions options_;
  bool view_ = true;
  ros::Publisher pub_;
  std::vector<ros::Subscriber> subs_;
  tf2_ros::TransformBroadcaster tf_;
  std::deque<WireShapeArray> shapes_;
  std::deque<PantographStateArray> states_;
  std::deque<ContactForceArray> forces_;
  ros::Time last_drawn_;
  bool drawn_any_ = false;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "replay_markers");
  ros::NodeHandle nh, pnh("~");
  try {
    ReplayMarkers node(nh, pnh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("replay_markers: %s", e.what());
    return 2;
  }
  return 0;
}
