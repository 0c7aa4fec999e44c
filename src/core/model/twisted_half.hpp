// One half of a wire whose condensed rotations are swept from both ends (Wire::twisted_meeting,
// twist_condensation): the generic step's (wire_band.cpp) and the fused kernel's pack
// (wire_packs.cpp) read the wire's band through it, so that both see the same numbers.
#pragma once

#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

// One half of a wire swept from both ends, as the fused kernel's lane reads it: station k is node
// k (lane 0) or node top - k of the wire mirrored (lane 1), whose couplings of a displacement with
// a rotation change sign and whose elements run backwards.
struct TwistedHalf {
  const Wire& w;
  int top;
  bool mirrored;
  int node(int k) const { return mirrored ? top - k : k; }
  double dww(int k) const { return w.d_ww[node(k)]; }
  double dwt(int k) const { return mirrored ? -w.d_wt[top - k] : w.d_wt[k]; }
  double eww(int k) const { return mirrored ? w.e_ww[top - k - 1] : w.e_ww[k]; }
  double ewt(int k) const { return mirrored ? -w.e_tw[top - k - 1] : w.e_wt[k]; }
  double etw(int k) const { return mirrored ? -w.e_wt[top - k - 1] : w.e_tw[k]; }
  double lower(int k) const { return mirrored ? w.twisted_lower[k] : w.tt_lower[k]; }
  double inv_pivot(int k) const { return mirrored ? w.twisted_inv_pivot[k] : w.tt_inv_pivot[k]; }
};

}  // namespace catenary_sim
