// The train's motion: its speed toward the commanded one, its front, the clock.
#include "engine/train_motion.hpp"

#include <cmath>

#include "engine/forces.hpp"

namespace catenary_sim {

double next_speed(const State& s, double dt) {
  const double dv = s.target_speed - s.speed, dvmax = s.max_acceleration * dt;
  return (s.max_acceleration <= 0.0 || std::fabs(dv) <= dvmax) ? s.target_speed : s.speed + std::copysign(dvmax, dv);
}

void advance_train(const Model& m, State& s, double dt) {
  s.speed = next_speed(s, dt);
  s.front += s.speed * dt;
  s.time += dt;
  ++s.steps;
  contact_forces(m, s, s.u.data(), nullptr);
}

}  // namespace catenary_sim
