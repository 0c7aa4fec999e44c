// A moving window's part of one wire (State::window for the vertical plane, LateralState::window
// for the lateral plane).
#pragma once

#include <vector>

namespace catenary_sim {

// The part of one wire a moving window integrates: nodes lo..hi (empty when hi < lo). Where the
// window cuts the wire (not at its anchors) the element outside is left out and a dashpot of the
// wire's impedance sqrt(T rhoA) absorbs the waves that leave.
struct WireWindow {
  int lo = 0, hi = -1;
  bool cut_lo = false, cut_hi = false;
  double lo_ww = 0, lo_wt = 0, lo_tt = 0, hi_ww = 0, hi_wt = 0, hi_tt = 0;  // outside element's share of the end blocks
  std::vector<double> tt_lower, tt_inv_pivot;  // LDL^T of the window's K_theta_theta
  // A wire swept from both ends (Wire::twisted) whose window holds an odd count of nodes: the
  // meeting's station (its middle, from lo), the mirrored half's factors by station (from hi) and
  // 1 / gamma; and the fused kernel's coefficients and factors in the two lanes (lay_out_twisted).
  // meet -1: one lane for this window.
  int meet = -1;
  std::vector<double> twisted_lower, twisted_inv_pivot, twisted_coef, twisted_factors;
  double inv_gamma = 0.0;
};

}  // namespace catenary_sim
