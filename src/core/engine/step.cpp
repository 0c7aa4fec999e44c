// The step: which integrator advances the line. Each path lives in its own file:
// explicit_step.cpp (eq. 19-21), centred_damping_step.cpp, implicit_step.cpp (Newmark).
#include "catenary_sim/core/engine/step.hpp"

#include "catenary_sim/core/engine/state.hpp"
#include "engine/centred_damping_step.hpp"
#include "engine/explicit_step.hpp"
#include "engine/implicit_step.hpp"

namespace catenary_sim {

StepStatus step(const Model& m, State& s) {
  if (s.status != StepStatus::kOk) return s.status;
  if (s.front + s.line_offset >= m.train_end) {
    s.status = StepStatus::kFinished;
    return s.status;
  }
  if (m.implicit) return implicit_step(m, s);
  if (m.scene.numerics.damping == DampingStep::kCentred) return centred_damping_step(m, s);
  return explicit_step(m, s);
}

}  // namespace catenary_sim
