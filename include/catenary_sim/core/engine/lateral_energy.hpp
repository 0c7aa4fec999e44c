// Energies of the 3-D line (lateral_energy.cpp): the constants of an undamped, windless free
// motion by which the partitioned step is checked.
#pragma once

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/engine/state.hpp"

namespace catenary_sim {

// Lateral energy without wind: 0.5 v M v + 0.5 y K y - load . y of the wires and lateral supports,
// plus what the lean adds to the droppers' potential at the current vertical state,
// V(e_z + e_lean) - V(e_z), and for a hinged arm's registration its spring's energy to the moved
// anchor and F0 times the travel (LateralRegistration) (J); constant in an undamped, windless
// free motion of the lateral plane alone (the vertical one held).
double lateral_energy(const Model& model, const State& state);

// Energy of the whole line, both planes, the droppers' shared potential V(e) counted once:
// kinetic, the wires' and supports' strain, less the constant loads' work (J). Constant in an
// undamped, windless free motion of a line without pantographs on the full line (no window).
double line_energy(const Model& model, const State& state);

}  // namespace catenary_sim
