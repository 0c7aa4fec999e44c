// The lateral plane's implicit gust lead (lateral_lead.cpp): in a turbulent wind, the wires ahead
// of the lateral window, up to the gust lead's end, stepped on their own so that a span has felt
// the gusts when the window reaches it.
//
// Ahead of the vertical window the line is at rest vertically, so its lateral plane is linear but
// for the wind's drag: the trapezoidal rule (Newmark average acceleration), unconditionally
// stable, steps it at the wind's refresh interval (LateralModel::lead_dt, 0.01 s at 5 Hz, some
// 20 of the window's steps) with one block-tridiagonal solve per wire, the centred damping step's
// factors with another shift:
//   (D + K) zeta = F + D y_n + (2 M / dt) v_n,  zeta = y_mid + beta v_mid,
//   D = M (2 / dt + alpha) / (dt / 2 + beta),  v_mid = (zeta - y_n) / (dt / 2 + beta),
//   v_{n+1} = 2 v_mid - v_n,  y_{n+1} = y_n + dt v_mid,
// C = alpha M + beta K (eq. 5) at the step's middle. The springs (steady arms, messenger supports)
// and each pendulum's own end are in the solve, the pendulums' coupling between the two wires at
// the predicted zeta, the wind's drag at v_n; at the lead's cuts the static force of the elements
// left out and the wire's impedance as a dashpot, as the window's. The window, as it moves on,
// takes each node it reaches from the lead, interpolated to its time; what the window's pantograph
// sends ahead does not return into the lead (one way: the window's front cut lets it leave).
#pragma once

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/engine/state.hpp"

namespace catenary_sim {

// Steps the lead until its time is at least t. True if a new position left the divergence limit
// (the lead keeps its last good step).
bool advance_lead(const Model& m, State& s, double t);

// Places the lead from the lateral window's last support to the gust lead's end (after
// sync_window), rebuilding its lists and factors when it moved: the nodes entering it start in
// the static state under the mean wind, at rest.
void sync_lead(const Model& m, State& s);

// Lateral DOF `dof` of the lead at time t (between its last two steps): position and velocity.
void lead_state_at(const Model& m, const State& s, int dof, double t, double* y, double* v);

// Endless line: moves the lead back with the block (shift_lateral_block), as the window; the
// nodes entering at its far end start in the static state.
void shift_lead(const Model& m, State& s);

}  // namespace catenary_sim
