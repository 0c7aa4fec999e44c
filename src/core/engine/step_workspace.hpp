// The step's workspace: buffers and caches the integrators write every step (engine/*_step.cpp),
// sized once by make_state() so that step() never allocates. Private to the engine: observers read
// the state's physical fields and accessors (state.hpp), never these.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace catenary_sim {

struct StepWorkspace {
  // Force and z = u + beta v of the step (the centred damping step keeps the wires' load in
  // `force` between steps: clear_point_forces).
  Eigen::VectorXd force, z;
  // Fused explicit step: the new displacements and velocities (swapped in, or copied back in the
  // window, once all are good); per node and lane of every wire pack the sweep's record (rotation
  // and band force: engine/wire_lanes.hpp; or the centred step's); the window's LDL^T factors laid
  // out as WireLanes::factors; the contact wire's nodes under the collectors this step.
  Eigen::VectorXd u_next, v_next;
  std::vector<double> sweep, sweep_factors;
  std::vector<int> point_node;
  // Centred damping in a moving window: per pack the factors of the window's node range, laid
  // out as WireLanes::centred_twin and centred_single (at centred_twin_at[pack] and
  // centred_single_at[pack]), rebuilt when the window moves; scratch for one wire's range.
  std::vector<double> centred_twin, centred_single, centred_scratch;
  std::vector<std::size_t> centred_twin_at, centred_single_at;
  // Implicit integrator only: the prediction, and the rank-1 corrections of the factorised
  // matrix A (contacts in touch add k0 g g^T, slack droppers take their stiffness out again),
  // each with its sparse g, its stiffness factor and its column A^-1 g.
  Eigen::VectorXd u_pred, v_pred, solve_tmp;
  std::vector<double> contact_solve;           // A^-1 g per contact in touch (they move: every step)
  std::vector<double> dropper_solve;           // A^-1 g per cache slot (A never changes: kept)
  std::vector<int> dropper_slot;               // per dropper: its cache slot, -1 if none
  std::vector<int> slot_dropper;               // per slot: its dropper, -1 if free
  std::vector<std::int64_t> slot_used;         // per slot: the step that last used it
  std::vector<int> correction_g_index, correction_g_count;
  std::vector<double> correction_g_value, correction_factor, correction_small;
  std::vector<const double*> correction_solve;
  // Condensed rotations of one wire.
  std::vector<double> theta;
  // Per collector and contact wire (ci * contact wires + wk): the station the contact patch below
  // was found for (NaN: none yet), its node count, and max_contact_nodes nodes and weights
  // (contact_patch, forces.hpp).
  std::vector<double> patch_x;
  std::vector<int> patch_count, patch_node;
  std::vector<double> patch_weight;
};

}  // namespace catenary_sim
