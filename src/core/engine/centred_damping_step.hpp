// The explicit step with centred Rayleigh damping (centred_damping_step.cpp; the scheme and its
// factors: centred_damping.hpp).
#pragma once

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/engine/state.hpp"

namespace catenary_sim {

// The explicit step with centred damping (centred_damping.hpp): the point forces on z = u + beta v
// as in the half-step scheme, then per wire pack the block-tridiagonal solve for zeta and the
// update (centred_sweep_pack; build_model gives such a model its packs), then the pantographs.
StepStatus centred_damping_step(const Model& m, State& s);

// A 3-D line's lateral centred substep taken along by the vertical step (step.cpp; in
// lateral_step.cpp): where the model has both planes' factors (LateralModel::centred_joint_twin,
// built only where the solve can be taken along), the lateral forces of the step's start (the wind refreshed for it) are
// set now, and the vertical step's solve of each lone wire then solves its lateral plane in a
// second lane; lateral_step solves the rest. False (nothing done) where it cannot.
bool take_centred_solve_along(const Model& m, State& s);

}  // namespace catenary_sim
