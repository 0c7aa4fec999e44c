// The fused explicit step's kernel (wire_lanes.cpp): one sweep pair per wire pack does the whole
// wire part of eq. 19-21 with the rotations condensed.
#pragma once

#include "catenary_sim/core/model/lateral.hpp"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/engine/state.hpp"
#include "model/wire_packs.hpp"

namespace catenary_sim {

// One pack over nodes lo..hi (hi >= lo + 1), the same range in every lane.
struct PackSweep {
  const WireLanes* pack = nullptr;
  const double* factors = nullptr;  // LDL^T of K_theta_theta over lo..hi (WireLanes::factors' layout)
  int lo = 0, hi = -1;
  // Diagonal band entries at lo and hi less the share of elements left out (a window's cut).
  double ww_lo[2] = {0, 0}, wt_lo[2] = {0, 0}, ww_hi[2] = {0, 0}, wt_hi[2] = {0, 0};
  const double* u[2] = {nullptr, nullptr};  // node 0 of each lane's wire (all in the state's arrays)
  const double* v[2] = {nullptr, nullptr};
  double* u_next[2] = {nullptr, nullptr};
  double* v_next[2] = {nullptr, nullptr};
  double* accel[2] = {nullptr, nullptr};
  double* record = nullptr;  // StepWorkspace::sweep at the pack's records: kept for the nodes with point forces
  double beta = 0.0, dt = 0.0, limit = 0.0;
  // The lateral plane (lateral.cpp) sweeps with the vertical pack's band and factors (the same
  // beam both ways) but its own load, mass-proportional damping and inverse mass, and the wind's
  // drag coefficient cw = 0.5 rho Cd d h: per node and lane kPlaneValues values in `plane`
  // ([node][value][lane], loaded whole like the coefficients). Null: the pack's own, no wind.
  const double* plane = nullptr;
  // Optional wind drag on the lateral plane, laid out as u: per node the wind's speed normal to the
  // wire W; the drag cw (W - v)|W - v| (the wire's own velocity v gives the aerodynamic damping) is
  // added to the load. Null: none.
  const double* wind[2] = {nullptr, nullptr};
  // A lone wire swept from both ends (Wire::twisted; the state's pointers at node lo): the
  // meeting's station (-1: one lane), its 1 / gamma, the two lanes' coefficients by station
  // (lay_out_twisted; `factors` holds theirs), and whether the records are in node order (a
  // window's) or by station (the whole wire's: WirePacks::dof_sweep_force).
  int twisted_meet = -1;
  double twisted_inv_gamma = 0.0;
  const double* twisted_coef = nullptr;
  bool node_records = false;
};

// z = u + beta v, the condensed rotations (forward and backward tridiagonal sweeps), the band
// force with the load and the mass-proportional damping, and the update of eq. 20-21, fused in
// one forward and one backward pass. The same IEEE operations in the same order as the generic
// step (condensed_band_force), so the results are bit-identical to it. Returns true if some new
// displacement is beyond the limit or not a number (the caller finds which).
// With wind, the load is (load - alpha m v) + (cw (W - v)) |W - v|, in that order.
// Runtime dispatch (GCC target_clones): x86-64-v4 (AVX-512), x86-64-v3 (AVX2) or the portable
// x86-64 baseline.
bool sweep_pack(const PackSweep& sweep);

// The vertical plane's sweep `vertical` and the lateral plane's `lateral` (PackSweep::plane set)
// of the same pack (one wire or two) over the same nodes, in twice its lanes (the band and its
// factors are the same both ways: loaded once, and every band operation does both planes): each
// plane gets what sweep_pack gives it alone, to the bit (lane by lane the same operations), but
// both planes' records are interleaved in `joint_record` (the pack's, per node [value][the
// vertical plane's lanes, then the lateral plane's]: WirePacks::dof_joint_force and
// LateralModel::joint_force_at find them) instead of at their PackSweep::record. Returns the
// vertical sweep's flag, the lateral's in `lateral_outside`.
bool sweep_pack_pair(const PackSweep& vertical, const PackSweep& lateral, double* joint_record, bool* lateral_outside);

// Sets up pack p's sweep over `windows` (per wire of `wires`, their factors interleaved in
// `window_factors`: the vertical plane's State::window or the lateral plane's own; null: the whole
// wires) on the state arrays x, v, x_next, v_next and accel, indexed by `wires`' w_dof (the
// vertical plane's Model::wires, or the lateral plane's, whose band is the same), its records in
// `records` (StepWorkspace::sweep). The ends take off the cut's share of the band (condensed_band_force's).
// False when the window holds no node of the pack.
bool setup_pack_sweep(const WireLanes& p, const std::vector<Wire>& wires, const std::vector<WireWindow>* windows,
                      const double* window_factors, double* records, const double* x, const double* v, double* x_next,
                      double* v_next, double* accel, PackSweep& a);

// The lateral plane's sweep of pack `pack` (its coefficients: LateralModel::planes) on the lateral
// state, its records in the vertical step's StepWorkspace::sweep (sweep_pack_pair's joint layout
// puts them elsewhere); false when the window holds no node of the pack.
bool setup_lateral_sweep(const Model& model, State& s, std::size_t pack, bool windowed, PackSweep& a);


}  // namespace catenary_sim
