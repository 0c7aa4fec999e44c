// Replay of a recording: rebuilds, from the recorded wire_shape, pantograph_state and contact_force
// of one instant, the part of a State that the markers draw, so that a replayed bag is drawn by the
// same to_markers() as the live pass (replay_markers node). Pure: no node handle, no clock.
#pragma once

#include <string>

#include "catenary_sim/ContactForceArray.h"
#include "catenary_sim/PantographStateArray.h"
#include "catenary_sim/WireShapeArray.h"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/engine/state.hpp"

namespace catenary_sim {
namespace ros_layer {

// Fills `s` (made by make_state(m)) from three messages of the same instant: the wires' vertical
// displacements at every node (linear interpolation of the recorded samples minus the design
// height, exact at the sampled nodes; every node when the recording's ~shape_resolution was 0),
// the line offset (endless line), the train kinematics, the pantograph masses, the uplift, the
// contact force per collector and contact wire, and the slack droppers (recomputed from the
// displacements with the core's tension criterion, the state of the droppers is not recorded).
// Returns "" on success, else what does not fit the model, naming the message field, the value and
// what was expected (usually: the recording is of another scene); `s` is then partly filled.
std::string state_from_messages(const Model& m, const WireShapeArray& shape, const PantographStateArray& state,
                                const ContactForceArray& force, State* s);

// "" when `given` (a replay's ~scene) is the line of `recorded` (the scene the recording carries)
// as drawn: the same supports, wires, droppers and design heights (meshes may differ); else the
// first difference, naming the wire or support and both values. A scene that differs in what the
// recorded messages do not show (a bridle's tension, the auxiliary's height, the supports'
// spacing) would be drawn wrongly without a word.
std::string scene_difference(const Model& given, const Model& recorded);

}  // namespace ros_layer
}  // namespace catenary_sim
