// A wire's nodes lo..hi whose condensed rotations are swept from both ends (Wire::twisted: the
// whole wire, or a moving window's part of it): the generic step's band force (wire_band.cpp) and
// the fused kernel's coefficients (wire_packs.cpp) read the band through TwistedHalf, so that both
// see the same numbers.
#pragma once

#include "catenary_sim/core/engine/wire_window.hpp"
#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

// What both halves share. Station k of the first half is node lo + k; of the second, node hi - k
// of the wire mirrored (x' = L - x negates each rotation). They meet at station `meet`, the middle
// node of an odd count.
struct TwistedRange {
  const Wire* w = nullptr;
  int lo = 0, hi = -1, meet = -1;
  // Station 0's diagonal blocks, less a window's cut share (condensed_band_force's ends), per half
  // (the second half's coupling negated).
  double end_ww[2] = {0, 0}, end_wt[2] = {0, 0};
  // Per half, by station: the LDL^T factors of K_theta_theta from its station 0.
  const double* lower[2] = {nullptr, nullptr};
  const double* inv_pivot[2] = {nullptr, nullptr};
  double inv_gamma = 0.0;  // 1 / gamma of the meeting row
};

// The whole wire (Wire::twisted_meeting), and a moving window's part of it (WireWindow::meet).
TwistedRange whole_wire_range(const Wire& w);
TwistedRange window_range(const Wire& w, const WireWindow& ww);

// One half: the mirrored one's couplings of a displacement with a rotation change sign and its
// elements run backwards.
struct TwistedHalf {
  const TwistedRange& r;
  bool mirrored;
  int node(int k) const { return mirrored ? r.hi - k : r.lo + k; }
  double dww(int k) const { return k == 0 ? r.end_ww[mirrored] : r.w->d_ww[node(k)]; }
  double dwt(int k) const { return k == 0 ? r.end_wt[mirrored] : mirrored ? -r.w->d_wt[node(k)] : r.w->d_wt[node(k)]; }
  double eww(int k) const { return mirrored ? r.w->e_ww[r.hi - k - 1] : r.w->e_ww[r.lo + k]; }
  double ewt(int k) const { return mirrored ? -r.w->e_tw[r.hi - k - 1] : r.w->e_wt[r.lo + k]; }
  double etw(int k) const { return mirrored ? -r.w->e_wt[r.hi - k - 1] : r.w->e_tw[r.lo + k]; }
  double lower(int k) const { return r.lower[mirrored][k]; }
  double inv_pivot(int k) const { return r.inv_pivot[mirrored][k]; }
};

// The mirrored half's factors over nodes lo..hi (an odd count) less the shares tt_lo, tt_hi of
// elements left out at the ends, by station (node hi - k) up to the meeting, into lower and
// inv_pivot; returns 1 / gamma of the meeting row.
double twist_range(const Wire& w, int lo, int hi, double tt_lo, double tt_hi, double* lower, double* inv_pivot);

// f -= K z over the range with its rotations condensed from both ends, in the fused kernel's order
// of operations; theta (the wire's nodes) returns the rotations.
void twisted_band_force(const TwistedRange& r, const double* z, double* f, double* theta);

}  // namespace catenary_sim
