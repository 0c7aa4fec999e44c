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
  // Hinged arms' registrations (registration_pull, lateral_step.cpp), set by make_lateral_state:
  // per registration the wire's lateral force on it in the state the pass starts from (N, F0),
  // and where held its band force's row (N/m per node, registration_count of them from the DOF
  // registration_first on).
  std::vector<double> registration_pull0, registration_row;
  std::vector<int> registration_first, registration_count;
  // m, per registration: where a held one was when the band sweep of the step's first substep
  // took it (the last step's place; the joint sweep runs before this step places it), so that the
  // point forces add row x (y - swept) on its row's nodes; equal to y once no sweep lags.
  std::vector<double> registration_swept;
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
  bool window_fused = false;  // the fused step can take the window (a pack's lanes over the same range)
  // The centred damping step in the window: per pack the factors of its range, laid out as
  // LateralModel::centred_twin and centred_single (at centred_twin_at[pack] and
  // centred_single_at[pack]), rebuilt by sync_window; scratch for one wire's range.
  std::vector<double> centred_twin, centred_single, centred_scratch;
  std::vector<std::size_t> centred_twin_at, centred_single_at;
  // The implicit gust lead's step (lateral_lead.cpp), rebuilt by sync_lead when the lead moved:
  // the pendulums in it, its cuts' static force, the diagonal D + springs + pendulums + the cuts'
  // dashpots over the shift (LateralModel::lead_mass and the dashpots) and the nodes where it
  // exceeds M (their extra times the shift), the held nodes, per pack its factors laid
  // out as centred_twin and centred_single; each lead step's force, new values, wind and the
  // field's points at its middle, and the solve's records.
  bool lead_dirty = true;
  std::vector<int> lead_droppers;
  int lead_dropper_count = 0;
  std::vector<int> lead_cut_node, lead_held, lead_extra_node, lead_dashpot_node;
  std::vector<double> lead_extra_diag, lead_dashpot;  // N/m: D's share of a node's diagonal extra; N s/m / lead_beta
  int lead_held_count = 0, lead_extra_count = 0, lead_dashpot_count = 0;
  std::vector<double> lead_cut_force;
  int lead_cut_count = 0;
  Eigen::VectorXd lead_plane_mass, lead_f, lead_y_next, lead_v_next, lead_accel, lead_wind;
  std::vector<double> lead_points, lead_twin, lead_single, lead_scratch, lead_record;
  std::vector<std::size_t> lead_twin_at, lead_single_at;
  // An endless line's lead: per DOF the field point before its station and the weight of the next
  // (WindField::locate, clamped to the held points as wind_on_nodes does), for the line offset,
  // the first held point and the placement they were found for.
  std::vector<int> lead_wind_point;
  std::vector<double> lead_wind_weight;
  double lead_wind_offset = 0.0;
  int lead_wind_first = -1;
  bool lead_wind_stale = true;
};

}  // namespace catenary_sim
