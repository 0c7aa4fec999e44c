// The lateral plane's moving window (lateral_window.cpp): the vertical plane's window, reaching a
// gust lead further ahead in a turbulent wind, with the static force of the elements left out.
#pragma once

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/engine/state.hpp"

namespace catenary_sim {

// Moving window: nodes from each cut inward that take the static force of the elements left out.
// The window's condensed stiffness differs from the line's only through the rotation at the cut,
// whose influence on K_theta_theta^-1 falls by about off-diagonal / diagonal (0.2-0.3 at 0.1-1 m
// elements of the reference wires) per element: after 32 nodes by under 1e-16.
constexpr int kCutLayer = 32;

// Calls body(i0, i1) on the lateral DOFs stepped: each wire's window, or the whole line.
template <class Body>
void over_stepped(const Model& m, const State& s, bool windowed, Body&& body) {
  if (!windowed) {
    body(0, m.lateral->n);
    return;
  }
  const LateralState& ls = s.lateral;
  for (std::size_t wi = 0; wi < m.lateral->wires.size(); ++wi)
    if (ls.window[wi].hi >= ls.window[wi].lo) {
      const int o = m.lateral->wires[wi].w_dof;
      body(o + ls.window[wi].lo, o + ls.window[wi].hi + 1);
    }
}

// The static force of the elements a window `ww` of lateral wire `wi` leaves out, on the nodes of
// its cut layers: appended to node/force from `count`, the new count returned; f and theta are
// scratch (f over the window's nodes is overwritten).
int add_cut_forces(const Model& m, std::size_t wi, const WireWindow& ww, int* node, double* force, int count, double* f,
                   double* theta);

// The support the gust lead reaches from support `from` (LateralModel::gust_lead seconds of travel
// at the state's speed, snapped outward to a support, at most the line's last).
int gust_lead_end(const Model& m, const State& s, int from);

// Moves the lateral window with the vertical one (and its lead), rebuilding its lists only when it
// moved (lateral_window.cpp).
void sync_window(const Model& m, State& s);

// The window's own point forces, first after the band: the cut layers' static force and, at the
// cuts, a dashpot of the wire's impedance sqrt(T rhoA) that lets the outgoing waves leave (the
// vertical plane's, add_wire_point_forces).
void add_window_forces(const Model& m, const State& s, const double* v, double* f);

}  // namespace catenary_sim
