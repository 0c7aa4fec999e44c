// Moving window internals (see window.cpp).
#pragma once

#include <algorithm>
#include <vector>

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/engine/state.hpp"
#include "model/centred_factors.hpp"
#include "model/wire_packs.hpp"

namespace catenary_sim {

// One wire's window over the supports at stations a <= b: its node range, the cut ends' share of
// the band and the LDL^T factors of its K_theta_theta (the vertical plane's window, and the lateral
// plane's, which may reach further ahead: lateral.cpp). Empty (hi < lo) unless it holds an element
// of the wire: two nodes or more.
void set_wire_window(const Wire& wire, double a, double b, WireWindow& window);

// The windows' factors interleaved per pack for the fused step (both lanes of a pack share the
// node range), laid out as WireLanes::factors at the pack's offset.
void interleave_window_factors(const std::vector<WireLanes>& packs, const std::vector<WireWindow>& windows,
                               double* sweep_factors);

// The centred damping step's factors of each pack's window range in `plane` (both lanes share it:
// a pack's wires are on the same node stations), pack k's at twin + twin_at[k] and single +
// single_at[k], laid out as WireLanes::centred_twin and centred_single; `scratch` for one wire's
// range. No allocation.
void factor_centred_windows(const CentredPlane& plane, const std::vector<WireLanes>& packs,
                            const std::vector<WireWindow>& windows, double* scratch, double* twin,
                            const std::vector<std::size_t>& twin_at, double* single,
                            const std::vector<std::size_t>& single_at);

// Whether DOF `dof` (numbered by `wires`' w_dof) lies in its wire's window.
bool in_windows(const std::vector<Wire>& wires, const std::vector<WireWindow>& windows, int dof);

// The entries of `order` (indices in line order, at stations `order_x`) between stations a and b
// that `keep(index)` accepts, written to `list` in that order; returns how many. Bisection to a:
// costs what lies between a and b, not the line. No allocation.
template <class Keep>
int select_between(const std::vector<int>& order, const std::vector<double>& order_x, double a, double b, Keep&& keep,
                   int* list) {
  int count = 0;
  for (std::size_t j = std::lower_bound(order_x.begin(), order_x.end(), a - 1e-6) - order_x.begin();
       j < order.size() && order_x[j] <= b + 1e-6; ++j)
    if (keep(order[j])) list[count++] = order[j];
  return count;
}

// Moves the window to the pantographs if they crossed into another span; no allocation.
void update_window(const Model& model, State& state);

// Endless line: once the rearmost collector has run Model::endless_shift_spans spans past
// Model::endless_home, moves the window's displacements, velocities and accelerations back that
// many spans (the block is periodic, so this is exact), a 3-D line's lateral state with them
// (shift_lateral_block), the train too, and adds the distance to State::line_offset. No allocation.
void shift_endless_block(const Model& model, State& state);

// A move of the endless block for a stitched line's stitch wires (one per support), in either
// plane's `windows`: each takes the state and window of the one `endless_shift_spans` supports on,
// in order, so that the destination is always behind the source (take(to, from, from's window),
// before `to`'s window changes); the last ones return to the static state (rest(wire, its window))
// with their window empty until the window is placed again.
template <class Take, class Rest>
void hand_over_clamped_wires(const Model& m, std::vector<WireWindow>& windows, Take&& take, Rest&& rest) {
  const std::vector<int>& stitch = m.sections.front().clamped_wires;
  const std::size_t spans = static_cast<std::size_t>(m.endless_shift_spans);
  for (std::size_t j = 0; j < stitch.size(); ++j) {
    WireWindow& ww = windows[stitch[j]];
    if (j + spans < stitch.size()) {
      const WireWindow& from = windows[stitch[j + spans]];
      take(stitch[j], stitch[j + spans], from);
      ww.lo = from.lo;
      ww.hi = from.hi;
    } else {
      rest(stitch[j], ww);
      ww.lo = 0;
      ww.hi = -1;
    }
  }
}

// Calls fn(dof) on the window's cut ends, supports and droppers (each DOF in the window by
// construction of its lists), or on every support and dropper of the line.
template <class Fn>
void for_each_point(const Model& m, const State& s, bool windowed, Fn&& fn) {
  if (windowed) {
    for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
      const WireWindow& ww = s.window[wi];
      if (ww.hi < ww.lo) continue;
      if (ww.cut_lo) fn(m.wires[wi].w_dof + ww.lo);
      if (ww.cut_hi) fn(m.wires[wi].w_dof + ww.hi);
    }
    for (int j = 0; j < s.window_spring_count; ++j) fn(m.springs[s.window_springs[j]].dof);
    for (int j = 0; j < s.window_dropper_count; ++j) {
      const Dropper& d = m.droppers[s.window_droppers[j]];
      fn(d.contact_dof);
      fn(d.messenger_dof);
    }
    for (int j = 0; j < s.window_clamp_count; ++j) {
      const WireClamp& c = m.clamps[s.window_clamps[j]];
      fn(c.lower_dof);
      fn(c.upper_dof);
    }
  } else {
    for (const SupportSpring& sp : m.springs) fn(sp.dof);
    for (const Dropper& d : m.droppers) {
      fn(d.contact_dof);
      fn(d.messenger_dof);
    }
    for (const WireClamp& c : m.clamps) {
      fn(c.lower_dof);
      fn(c.upper_dof);
    }
  }
}

// The index of the last new displacement (`u_new`, by default StepWorkspace::u_next) beyond the
// divergence limit (or not a number), scanned in the generic step's order over the window's nodes
// or every DOF; -1 if none.
int last_beyond(const Model& model, const State& state, bool windowed, const double* u_new = nullptr);

// Copies the window's new values back (outside the window the new buffers hold nothing current).
void commit_window(const Model& model, State& state, const double* u_new, const double* v_new);

// -K z over the window's nodes of one wire (condensed rotations, cut ends left free).
void wire_elastic_force_window(const Wire& wire, const WireWindow& window, const double* z, double* f, double* theta);

}  // namespace catenary_sim
