// The explicit step with centred Rayleigh damping (NumericsSpec::damping kCentred): its factors and
// its fused sweep. The step itself (engine/step.cpp, centred_damping_step):
//   M (v_{n+1/2} - v_{n-1/2}) / dt = R_n - alpha M (v_{n+1/2} + v_{n-1/2}) / 2 - K zeta,
//   zeta = u_n + beta (v_{n+1/2} + v_{n-1/2}) / 2,
// C = alpha M + beta K (eq. 5) taken at t_n to second order where eq. 19-21 take v_{n-1/2}, the
// rotations condensed on zeta as they are on u + beta v. With v_{n+1/2} = 2 (zeta - u_n) / beta -
// v_{n-1/2}: (D + K) zeta = R_n + D u_n + (2 M / dt) v_{n-1/2}, D = M (2 / (beta dt) + alpha / beta),
// one block-tridiagonal solve per wire over its (w, theta) node pairs, factorised once. Central
// differences with centred damping are stable up to the undamped limit 2 / omega_max whatever the
// damping, where the half-step damping of the shortest mesh modes sets a limit falling like
// 1 / (beta omega_max^2). Point forces (supports, droppers, pantographs, contact) as in the half-step.
#pragma once
#include "catenary_sim/core/model/model.hpp"
#include "model/centred_factors.hpp"
#include "catenary_sim/core/engine/state.hpp"
#include "model/wire_packs.hpp"

namespace catenary_sim {

// A plane's arrays as one lane of a sweep reads and writes them, from the lane's first node on:
// u, v, f (the load and point forces), and the new values u_next, v_next, accel.
struct CentredArrays {
  const double *u = nullptr, *v = nullptr;
  double *f = nullptr, *u_next = nullptr, *v_next = nullptr, *accel = nullptr;
  CentredArrays at(int dof) const { return {u + dof, v + dof, f + dof, u_next + dof, v_next + dof, accel + dof}; }
};

// One solve and update in one or two lanes: a pack's wires in either plane, or one wire's
// vertical and lateral planes at once (the factors of each lane its own), each lane `nodes` nodes
// from lane[k] on, with the factors of that range (twin, single) and the step's records (4 values
// per node and lane). The lanes share dt, the velocity ratio (2 / dt) / D per mass, beta and the
// limit. Returns a bit per lane (bit k: lane k) whose new displacements left the limit or are not
// numbers; 0 when all are good.
struct CentredSweep {
  int lanes = 1;
  CentredArrays lane[2];
  int nodes = 0;
  double dt = 0.0, v_ratio = 0.0, beta = 0.0, limit = 0.0;  // v_ratio: (2 / dt) / D per mass
  const double *twin = nullptr, *single = nullptr;
  double* record = nullptr;
};
int centred_sweep(const CentredSweep& sweep);

// One wire pack's solve and update (both wires in lanes): reads u, v and the point forces in
// state.force (zeroing them there for the next step), writes u_next, v_next and accel. Returns
// true if a new displacement is beyond the limit or not a number.
bool centred_sweep_pack(const Model& m, const WireLanes& pack, State& s);
// One lone wire's (pack `pack`) vertical plane in lane 0 and lateral plane in lane 1, with
// LateralModel::centred_joint_*: the vertical values as centred_sweep_pack reads and writes them,
// the lateral ones as the lateral centred substep does (its forces in LateralWorkspace::f). Returns
// centred_sweep's bits: 1 the vertical plane left the limit, 2 the lateral plane.
int centred_sweep_both_planes(const Model& m, std::size_t pack, State& s);

// Whether pack `pack`'s lateral solve is one the vertical step takes along
// (LateralModel::centred_joint_twin exists for it): centred_sweep_both_planes solves it, the
// lateral step then leaves it.
inline bool joins_centred(const Model& m, std::size_t pack) {
  return m.lateral && pack < m.lateral->centred_joint_twin.size() && !m.lateral->centred_joint_twin[pack].empty();
}
// The same over the pack's nodes lo..hi (a moving window, both lanes the same range) with that
// range's factors (factor_centred_range).
bool centred_sweep_pack(const Model& m, const WireLanes& pack, State& s, int lo, int hi, const double* twin,
                        const double* single);


}  // namespace catenary_sim
