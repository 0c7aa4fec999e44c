// The turbulent wind on the lateral plane's nodes (lateral_wind.cpp): the field's values held,
// refreshed every kWindRefreshShare of its sample time, on the nodes the lateral step moves.
#pragma once

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/engine/state.hpp"

namespace catenary_sim {

// The turbulent field's values: a finite line's in the model, an endless line's in its state.
const WindFieldBuffer& field_values(const Model& m, const State& s);

// An endless line's field generated up to the point after the block's last node at the line
// offset `offset` (WindField::held keeps the block's first node's point).
void extend_endless_field(const Model& m, State& s, double offset);

// The wind's speed normal to nodes i0..i1-1 of the field's last sample (LateralState::wind_points;
// zero before the first refresh: the mean wind).
void refresh_wind(const Model& m, State& s, int i0, int i1);
// The same from the field's points `points` (at one time, WindFieldBuffer::at_time) into W.
void wind_on_nodes(const Model& m, const State& s, const double* points, int i0, int i1, double* W);

// The turbulent wind on the nodes stepped at time t, if a refresh is due: the wind's speed normal
// to each node's wire, W = (U + u') sin(angle), is refreshed every kWindRefreshShare of the field's
// sample time (it is linear between samples 0.1 s apart at the default 5 Hz); the drag on the
// moving wire is taken every step.
void refresh_wind_if_due(const Model& m, State& s, double t, bool windowed);

// The same, before the vertical step, for a sweep that takes the lateral plane along: the wind of
// the lateral step's start, t0 as lateral_step computes it after the vertical step's s.time += dt
// (the same rounding), so that lateral_step then finds the refresh done (the same values, once).
inline void refresh_wind_before_joint_step(const Model& m, State& s) {
  refresh_wind_if_due(m, s, (s.time + m.dt) - m.dt, false);
}

}  // namespace catenary_sim
