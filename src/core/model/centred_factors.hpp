// The factors of the explicit step with centred Rayleigh damping (engine/centred_damping.hpp):
// (D + K) zeta = R_n + D u_n + (2 M / dt) v_{n-1/2}, D = M (2 / (beta dt) + alpha / beta), one
// block-tridiagonal solve per wire over its (w, theta) node pairs, factorised once with the model.
#pragma once

#include "catenary_sim/core/model/model.hpp"
#include "model/wire_packs.hpp"

namespace catenary_sim {

// Per node and lane of the solve (WireLanes::centred_*, in the twisted order),
// eliminated from both ends toward the meeting node k = centred_meeting_node(n) (a twisted
// factorisation: two independent recurrences per wire), as a recurrence on c_i = S_i y_i (S_i the
// inverse pivot block): c_i = s_i r_i - G_i c_prev, with s_i the first column of S_i (the rotation
// entry of r is 0) and G (2x2, row-major); then zeta_i = c_i - P_i zeta_next. Below k the same
// from the other end; at k: zeta_k = s r_k - G c_{k-1} - P c'_{k+1}. Then the coefficient a of
// u + ratio v in r (D_i, or 1 on a fixed node, whose row is zeta = u). The load is not here: the
// state's force vector holds it on the wires between steps, and the point forces on top.
enum { kCdG, kCdS = 4, kCdP = 6, kCdU = 10, kCdValues };
int centred_meeting_node(int nodes);

// D per unit mass for a step dt: 2 / (beta dt) + alpha / beta.
double centred_shift(const Model& m, double dt);

// Fills the packs' WireLanes::centred_* and WirePacks::centred_* (every wire is in a pack) for
// m.dt; needs beta > 0.
void factor_centred_damping(const Model& m, WirePacks& packs);

// A plane's wires for the centred step: the vertical plane's (Model::wires, mass, inv_mass) or the
// lateral plane's (LateralModel), with D per unit mass for the plane's step (centred_shift).
struct CentredPlane {
  const std::vector<Wire>* wires = nullptr;
  const double* mass = nullptr;      // kg per DOF of the plane (Wire::w_dof numbers them)
  const double* inv_mass = nullptr;  // 0 on a held node, whose row is zeta = u
  double shift = 0.0;
};

// The factors of one lane of `pack` over its wire's nodes lo..hi in `plane` (the whole wire, or a
// moving window's part), laid out as WireLanes::centred_twin and centred_single are, for the
// range's hi - lo + 1 nodes. `end_share`: null, or the outer elements' shares of the end nodes'
// diagonal blocks left out where a window cuts the wire (ww, wt, tt at lo, then at hi; 0 at an
// uncut end), as in the window's band force. `scratch` holds kCdValues per node of the range. No
// allocation.
void factor_centred_range(const CentredPlane& plane, const WireLanes& pack, int lane, int lo, int hi,
                          const double end_share[6], double* scratch, double* twin, double* single);

}  // namespace catenary_sim
