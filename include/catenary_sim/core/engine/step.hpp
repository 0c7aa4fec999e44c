// The step (MuJoCo's mj_step to the Model and State): one fixed dt of the whole line.
#pragma once

namespace catenary_sim {

struct Model;
struct State;
enum class StepStatus;

// Advances the line one fixed dt: the vertical plane with the model's integrator (the explicit
// central differences of eq. 19-21 with the half-step velocity, the same with centred damping, or
// implicit Newmark), then on a 3-D line (Model::lateral) its lateral plane (lateral_step.hpp).
// Never reads a clock, never allocates, never logs. Returns the state's status; a stopped state
// stays stopped.
StepStatus step(const Model& model, State& state);

// The vertical plane alone, a 3-D line's lateral plane held where it is (its droppers keep the
// lean of LateralState::dropper_stretch): for studies of the vertical plane's answer to a given
// lean. A pass steps with step().
StepStatus vertical_step(const Model& model, State& state);

// The instruction set the fused explicit step's runtime dispatch chose on this machine:
// "x86-64-v4" (AVX-512), "x86-64-v3" (AVX2) or "default" (the x86-64 baseline). All give the
// same bits.
const char* sweep_pack_isa();

}  // namespace catenary_sim
