// A pass's initial state: the model's static solve (model/statics.cpp) under the state's loads.
#include "catenary_sim/core/engine/initial_state.hpp"

namespace catenary_sim {

PantographLoads pantograph_loads(const Model& m, const State& s) {
  PantographLoads loads;
  loads.front = s.front;
  loads.uplift = s.uplift;
  loads.external_force = s.external_force;
  loads.air_speed_squared.resize(m.pantographs.size());
  for (std::size_t i = 0; i < m.pantographs.size(); ++i) loads.air_speed_squared[i] = air_speed_squared(s, i);
  return loads;
}

void solve_initial_state(const Model& m, State& s, bool roof_springs) {
  const Eigen::VectorXd u = solve_static_equilibrium(m, pantograph_loads(m, s), roof_springs);
  s.u = u;  // into the state's own storage: its size is the model's
  s.v.setZero();  // eq. 24
  if (m.lateral && !s.lateral.registration_force.empty()) place_registrations(m, s);
}

}  // namespace catenary_sim
