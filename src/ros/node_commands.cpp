// The pass node's inputs: cmd/train_speed, cmd/uplift_force, the ~reset, ~set_paused and ~step
// services and dynamic_reconfigure. Each refusal names the value and what is allowed, and leaves
// the pass as it was.
#include "catenary_sim/ros/node.hpp"

#include <cmath>
#include <sstream>
#include <string>

namespace catenary_sim {
namespace ros_layer {

namespace {
// The answer of set_paused false and step once the pass has ended (pass_status "ended").
constexpr const char* kEndedMessage = "the pass has ended; reset to run again";
}  // namespace

void SimulationNode::on_reconfigure(NodeConfig& c, uint32_t) {
  // The ranges of the .cfg are those of the parameters; dynamic_reconfigure clamps to them, but
  // NaN passes its clamp (it compares false): refused here, the value in effect kept and
  // published back.
  const NodeConfig lo = NodeConfig::__getMin__(), hi = NodeConfig::__getMax__();
  auto take = [](const char* name, double& asked, double min, double max, double& kept) {
    if (std::isfinite(asked)) {
      kept = asked;
      return;
    }
    ROS_ERROR("catenary_sim: %s = %s rejected: allowed %g to %g; kept %g", name, format_given(asked).c_str(), min, max, kept);
    asked = kept;
  };
  if (std::isfinite(c.real_time_factor) && c.real_time_factor != params_.real_time_factor) reanchor();
  take("real_time_factor", c.real_time_factor, lo.real_time_factor, hi.real_time_factor, params_.real_time_factor);
  take("vertical_scale", c.vertical_scale, lo.vertical_scale, hi.vertical_scale, params_.vertical_scale);
  take("lateral_scale", c.lateral_scale, lo.lateral_scale, hi.lateral_scale, params_.lateral_scale);
  take("publish_rate", c.publish_rate, lo.publish_rate, hi.publish_rate, params_.publish_rate);
  take("shape_rate", c.shape_rate, lo.shape_rate, hi.shape_rate, params_.shape_rate);
  take("marker_rate", c.marker_rate, lo.marker_rate, hi.marker_rate, params_.marker_rate);
  std::string err;
  if (sim_->set_max_acceleration(c.max_acceleration, &err)) {
    params_.max_acceleration = c.max_acceleration;
  } else {
    ROS_ERROR("catenary_sim: max_acceleration = %s rejected: %s", format_given(c.max_acceleration).c_str(), err.c_str());
    c.max_acceleration = params_.max_acceleration;  // the server publishes the value in effect
  }
}

void SimulationNode::on_speed(const std_msgs::Float64::ConstPtr& msg) {
  // The range is checked here too, for a message with %g numbers (the core's has std::to_string's
  // "200.000000"); the core's check stays the authority.
  const double v = msg->data;
  if (const std::string e = speed_command_error(sim_->model().scene, v); !e.empty()) {
    ROS_ERROR_THROTTLE(1.0, "catenary_sim: %s; command ignored", e.c_str());
    return;
  }
  std::string err;
  if (!sim_->set_target_speed(v, &err)) {
    ROS_ERROR_THROTTLE(1.0, "catenary_sim: cmd/train_speed: %s; command ignored", err.c_str());
    return;
  }
  if (const std::string w = speed_warning(sim_->model(), v); !w.empty()) ROS_WARN_THROTTLE(5.0, "catenary_sim: %s", w.c_str());
  have_command_ = true;
  last_command_wall_ = ros::WallTime::now();
  // A new speed after the end of a held pass does not restart it: use ~reset.
}

void SimulationNode::on_uplift(const std_msgs::Float64MultiArray::ConstPtr& msg) {
  const std::size_t np = sim_->model().pantographs.size();
  const std::size_t n = msg->data.size();
  if (n != 1 && n != np) {
    if (np == 1)
      ROS_ERROR_THROTTLE(1.0, "catenary_sim: cmd/uplift_force: %zu values rejected: the scene has one pantograph, "
                         "send 1 value; command ignored", n);
    else
      ROS_ERROR_THROTTLE(1.0, "catenary_sim: cmd/uplift_force: %zu values rejected: send 1 (all pantographs) or %zu "
                         "(one per pantograph); command ignored", n, np);
    return;
  }
  // Check every value first so that a rejected command leaves the state unchanged.
  for (std::size_t i = 0; i < n; ++i) {
    const double f = msg->data[i];
    if (!std::isfinite(f) || f < 0.0 || f > Simulation::kMaxUplift) {
      ROS_ERROR_THROTTLE(1.0, "catenary_sim: cmd/uplift_force[%zu] = %s N rejected: allowed 0 to %g N; command ignored",
                         i, format_given(f).c_str(), Simulation::kMaxUplift);
      return;
    }
  }
  std::string err;
  for (std::size_t i = 0; i < n; ++i) {
    if (!sim_->set_uplift(n == 1 ? -1 : static_cast<int>(i), msg->data[i], &err)) {
      ROS_ERROR_THROTTLE(1.0, "catenary_sim: cmd/uplift_force: %s", err.c_str());  // not reached after the check
      return;
    }
  }
  have_command_ = true;
  last_command_wall_ = ros::WallTime::now();
}

bool SimulationNode::on_reset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  sim_->reset(true);
  restart_recording();
  ended_ = false;
  reanchor();
  publish(true);
  std::ostringstream s;
  s << "new pass from the start at t = " << sim_->state().time << " s (time keeps running)";
  res.success = true;
  res.message = s.str();
  ROS_INFO("catenary_sim: reset: %s", res.message.c_str());
  return true;
}

bool SimulationNode::on_set_paused(std_srvs::SetBool::Request& req, std_srvs::SetBool::Response& res) {
  // After the end (at_end stop, or a divergence) nothing runs until ~reset, whatever the pause
  // says: the answer agrees with pass_status.
  if (ended_ && !req.data) {
    res.success = false;
    res.message = kEndedMessage;
    return true;
  }
  if (!req.data && paused_) reanchor();
  paused_ = req.data;
  res.success = true;
  res.message = paused_ ? (ended_ ? std::string("paused (the pass has ended; a reset starts the next pass paused)")
                                  : std::string("paused"))
                        : "running";
  return true;
}

bool SimulationNode::on_step(Step::Request& req, Step::Response& res) {
  res.total_steps = sim_->state().steps;
  res.sim_time = sim_->state().time;
  res.steps_advanced = 0;
  if (ended_) {
    res.success = false;
    res.message = std::string("rejected: ") + kEndedMessage;
    return true;
  }
  if (!paused_) {
    res.success = false;
    res.message = "rejected: the simulation is running; call ~set_paused true first";
    return true;
  }
  if (req.steps < 1 || req.steps > kMaxStepsPerCall) {
    res.success = false;
    res.message = "steps = " + std::to_string(req.steps) + " rejected: allowed 1 to " + std::to_string(kMaxStepsPerCall);
    return true;
  }
  res.steps_advanced = do_steps(req.steps, nullptr);
  res.total_steps = sim_->state().steps;
  res.sim_time = sim_->state().time;
  res.success = res.steps_advanced == req.steps;
  res.message = res.success ? "ok" : "stopped early: " + sim_->status_message();
  // With at_end exit the main loop ends the pass once this reply has gone: shutting down inside
  // the callback would leave the caller without one.
  if (params_.at_end != AtEnd::kExit) handle_end();
  publish(true);
  return true;
}

}  // namespace ros_layer
}  // namespace catenary_sim
