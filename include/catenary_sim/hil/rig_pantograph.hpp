// The pantograph of the virtual rig: the scene's lumped pantograph (eq. 9: masses, springs and
// dampers head first, the uplift on the lowest mass, the contact spring k0 of eq. 22 with loss of
// contact, eq. 25) integrated on its own with the core's explicit central differences, against
// the wire heights it receives (hil/contact_point or a UDP contact-point packet). Pure (no ROS,
// no clock): gtest-able, and usable in a rig controller without ROS.
//
// Fed every step with the wire under it and applied with no delay, it reproduces the core's
// internal lumped pantograph exactly (test_ros_hil): the same equations in the same order.
#pragma once

#include <cstdint>
#include <vector>

#include "catenary_sim/core/scene/scene.hpp"

namespace catenary_sim {
namespace hil {

// The contact wire under one collector (one entry of ContactPoint's per-wire arrays).
struct WirePoint {
  bool on_wire = false;
  double height = 0.0;         // m, absolute
  double path_velocity = 0.0;  // m/s, rate of change of `height` seen by the moving pantograph
};

class RigPantograph {
 public:
  // `spec`: a lumped pantograph (type lumped, at least one mass); `contact_stiffness`: k0 (N/m,
  // the scene's contact.stiffness). Throws std::invalid_argument otherwise.
  RigPantograph(const PantographSpec& spec, double contact_stiffness);

  // Static equilibrium pressed against `points` (the wire at rest), every mass at rest: the total
  // contact force equals the uplift at `speed` (static_uplift + aero_coefficient speed^2), as in
  // the core's initial state (eq. 23, roof spring relaxed there). Displacements count from here.
  void reset(const std::vector<WirePoint>& points, double speed);

  // Total contact force (N): over the points on a wire, max(0, k0 (head - y)) with each height
  // extrapolated `ahead` s along its path velocity (eq. 22 with eq. 25, one contact per
  // collector and wire, as the core's lumped pantograph).
  double contact_force(const std::vector<WirePoint>& points, double ahead = 0.0) const;

  // One step of dt (the core's scheme: half-step velocities, dampers on the half-step velocity):
  // the springs and dampers, the uplift at `speed` on the lowest mass, -contact_force on the head.
  void step(double dt, double contact_force, double speed);

  double head_height() const { return head_static_ + d_[0]; }   // m, absolute
  const std::vector<double>& displacement() const { return d_; }  // m, from the static state, head first
  const std::vector<double>& velocity() const { return v_; }      // m/s, half-step, head first
  double static_force() const { return static_force_; }           // N, contact force at reset
  const PantographSpec& spec() const { return spec_; }
  double contact_stiffness() const { return k0_; }

 private:
  PantographSpec spec_;
  double k0_ = 0.0;
  double head_static_ = 0.0;   // m, head height at the static state
  double static_force_ = 0.0;  // N, the preload of the springs between masses
  std::vector<double> d_, v_, f_;
};

// The rig's side of the loop with simulated pantographs, shared by virtual_rig (topics) and
// UdpVirtualRig (UDP): at each contact point received, every pantograph is stepped from the
// previous point's step to the new one against the previous point's wire (extrapolated along its
// path velocity, as an actuator tracking it would, or held), then the new wire is taken; the force
// to send is the contact force on it. A new pass, a step back or another number of pantographs
// starts again from the static state.
class RigStepper {
 public:
  explicit RigStepper(bool extrapolate = true) : extrapolate_(extrapolate) {}
  bool needs_restart(std::uint32_t pass, std::uint64_t step, std::size_t pantographs) const {
    return !have_ || pass != pass_ || step < step_ || pantographs != points_.size() || step - step_ > 1000000;
  }
  // `rigs` (one per external pantograph, in order) pressed on `points` at their static state.
  void restart(std::vector<RigPantograph> rigs, std::vector<std::vector<WirePoint>> points, std::uint32_t pass,
               std::uint64_t step, double dt, double speed);
  // Steps every pantograph up to `step`, then takes `points` (swapped in).
  void advance(std::uint64_t step, std::vector<std::vector<WirePoint>>& points, double dt, double speed);
  void clear() { have_ = false; }
  double force(std::size_t i) const { return rigs_[i].contact_force(points_[i]); }
  std::size_t size() const { return rigs_.size(); }
  bool have() const { return have_; }
  std::uint32_t pass() const { return pass_; }
  std::uint64_t step() const { return step_; }
  double dt() const { return dt_; }

 private:
  bool extrapolate_ = true, have_ = false;
  std::vector<RigPantograph> rigs_;
  std::vector<std::vector<WirePoint>> points_;
  std::uint32_t pass_ = 0;
  std::uint64_t step_ = 0;
  double dt_ = 0.0, speed_ = 0.0;
};

}  // namespace hil
}  // namespace catenary_sim
