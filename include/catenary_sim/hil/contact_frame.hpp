// What the HIL loop sends its rig each period: the motion of the wire under every external
// pantograph (a PointFrame), computed from the core's state.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "catenary_sim/core/engine/state.hpp"
#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {
namespace hil {

// Indices of the external pantographs of a model, in scene order.
std::vector<int> external_pantographs(const Model& m);

// The motion of the wire under one external pantograph: what a rig imposes on it.
struct PantographPoint {
  std::string name;
  double position = 0.0;       // m along the line
  // The lowest contact wire under each collector (the one a force-driven collector pushes),
  // averaged over the collectors; the scene's contact-wire height at rest with none under it.
  double height = 0.0, velocity = 0.0, acceleration = 0.0, path_velocity = 0.0;
  double applied_force = 0.0;  // N, total force applied in the last step
  double measurement_age = -1.0;  // s, age of the measurement in effect (-1: none)
  std::vector<ContactPointMotion> wires;  // per collector and contact wire, collector-major
};

// Mode codes as in ContactPointArray.msg and udp_packets.h.
enum class Mode : std::uint8_t { kWaiting = 0, kRunning = 1, kHold = 2, kEnded = 3, kPaused = 4 };
const char* mode_name(Mode m);

// The contact points of one period: every external pantograph.
struct PointFrame {
  double simulation_time = 0.0, dt = 0.0, speed = 0.0;
  std::uint64_t step = 0, measurement_step = 0;
  std::uint32_t pass_count = 0, steps_per_period = 1;
  Mode mode = Mode::kWaiting;
  std::vector<PantographPoint> pantographs;
};
// Fills `out` (reusing its storage) from the state: mode kRunning, no measurement.
void compute_frame(const Model& m, const State& s, int steps_per_period, PointFrame& out);
bool all_finite(const PointFrame& f);

}  // namespace hil
}  // namespace catenary_sim
