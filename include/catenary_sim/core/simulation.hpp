// The public face of the core: a pass of one scene, stepped at a fixed dt, with validated
// commands (train speed, uplift), reset, and snapshots of the initial state.
#pragma once

#include <string>

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/scene/scene.hpp"
#include "catenary_sim/core/engine/state.hpp"

namespace catenary_sim {

class Simulation {
 public:
  // Builds the model and the initial state (eq. 23, 24). Throws SceneError.
  explicit Simulation(const Scene& scene);

  const Model& model() const { return model_; }
  const State& state() const { return state_; }

  // The vertical step, then (3-D line) the lateral one; a run stopped by either stays stopped.
  StepStatus step() { return catenary_sim::step(model_, state_); }
  bool finished() const { return state_.status == StepStatus::kFinished || state_.status == StepStatus::kDewired || state_.front + state_.line_offset >= model_.train_end; }
  // Human-readable status, naming the DOF and time of a divergence.
  std::string status_message() const;

  // New pass from the start at the initial static state. The clock keeps running when
  // keep_time is true (a live node must never move time backwards); commands stay in effect.
  void reset(bool keep_time = true);

  // Commands. On rejection they return false, fill `error` with the value and the allowed range,
  // and leave the state untouched.
  bool set_target_speed(double speed_mps, std::string* error);
  bool set_max_acceleration(double accel_mps2, std::string* error);
  // set_max_acceleration's check of a value alone: empty when allowed, else its error.
  static std::string max_acceleration_error(double accel_mps2);
  // pantograph < 0: all pantographs.
  bool set_uplift(int pantograph, double force_n, std::string* error);

  // Force measured on the real pantograph of an external (hardware-in-the-loop) pantograph.
  // Readings down to kMinExternalForce are taken as 0 (load-cell noise without contact: a
  // collector cannot pull); NaN, inf and values outside [kMinExternalForce, kMaxExternalForce] are
  // rejected and leave the state unchanged.
  bool set_external_force(int pantograph, double force_n, std::string* error);
  // set_external_force's check of a value alone: empty when allowed, else its error.
  static std::string external_force_error(double force_n);

  static constexpr double kMinExternalForce = -50.0;  // N
  static constexpr double kMaxExternalForce = 2000.0; // N
  static constexpr double kMaxSpeed = kMaxTrainSpeed;  // m/s, the ceiling; below it train_speed_limit (scene.hpp)
  static constexpr double kMaxUplift = 1000.0;  // N
  static constexpr double kMaxAcceleration = 20.0;  // m/s^2, set_max_acceleration's ceiling (about 2 g)

  // A dt above this share of the stability estimate is what a divergence message blames first.
  static constexpr double kStepNearEstimate = 0.95;

 private:
  std::string divergence_cause() const;
  Model model_;
  State initial_;
  State state_;
};

}  // namespace catenary_sim
