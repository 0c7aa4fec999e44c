// The lateral step's workspace: buffers, lists and caches the lateral step (engine/lateral_*.cpp)
// and the vertical step that takes its sweep along (explicit_step.cpp) write every step, sized
// once by make_lateral_state() so that step() never allocates. Private to the engine: nothing in
// it carries the lateral plane from one step to the next that is not rebuilt from the state
// (LateralState, lateral_step.hpp) before it is read, so observers and snapshots never need it.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace catenary_sim {

struct LateralWorkspace {
  // N per node, the force of a substep; m, z = y + beta v (the generic step's, eq. 20-21).
  Eigen::VectorXd f, z;
  // The fused step's new displacements (m), velocities (m/s) and accelerations (m/s^2): swapped
  // in, or copied back in the window, once all are inside the divergence limit.
  Eigen::VectorXd y_next, v_next, accel;
  // Both planes' sweep records when the vertical step takes the lateral sweep along
  // (step_both_planes, sweep_pack_pair's joint layout), and that hand-over: `join` while the
  // vertical step may take it, `joined` when it did, with the lateral sweep's divergence hint.
  std::vector<double> sweep;
  bool join = false, joined = false, joined_outside = false;
  std::int64_t joined_steps = 0;  // diagnostic: steps whose lateral sweep the vertical step took along
  // Condensed rotations of one wire.
  std::vector<double> theta;
  // Per dropper: 1 where the lean acts on its tension, 0 outside the vertical plane's window
  // (set from State::window_droppers at every windowed step; all 1 without a window).
  std::vector<double> lean_weight;
  // The moving window's lists, rebuilt by sync_window from its placement (LateralState::window):
  // the factors interleaved for the fused step; the springs, the droppers' pendulums and the
  // stitch wires' clamps in it (first *_count entries; pendulum k is dropper k, clamp k
  // Model::clamps[k]); the static force (N) of the left-out elements on the nodes near the cuts;
  // the nodes with point forces for the fused step.
  bool window_dirty = true;  // lists and factors to rebuild (the endless block moved, or none yet)
  std::vector<double> sweep_factors;
  std::vector<int> window_springs, window_droppers, window_clamps;
  int window_spring_count = 0, window_dropper_count = 0, window_clamp_count = 0;
  std::vector<int> cut_node;
  std::vector<double> cut_force;
  int cut_count = 0;
  std::vector<int> window_points;
  int window_point_count = 0;
  bool window_fused = false;  // the fused step can take the window (every wire's range two nodes or more)
  // The centred damping step in the window: per pack the factors of its range, laid out as
  // LateralModel::centred_twin and centred_single (at centred_twin_at[pack] and
  // centred_single_at[pack]), rebuilt by sync_window; scratch for one wire's range.
  std::vector<double> centred_twin, centred_single, centred_scratch;
  std::vector<std::size_t> centred_twin_at, centred_single_at;
};

}  // namespace catenary_sim
