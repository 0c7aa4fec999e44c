// The step (MuJoCo's mj_step to the Model and State): one fixed dt of the whole line.
#pragma once

namespace catenary_sim {

struct Model;
struct State;
enum class StepStatus;

// Advances one fixed dt with the model's integrator: the explicit central differences of eq. 19-21
// (half-step velocity), the same with centred damping, or implicit Newmark. Never reads a clock,
// never allocates, never logs. Returns the state's status; a stopped state stays stopped.
StepStatus step(const Model& model, State& state);

}  // namespace catenary_sim
