// The virtual rig's pantograph (hil::RigPantograph, hil/rig_pantograph.hpp) fed from
// hil/contact_point.
#pragma once

#include <vector>

#include "catenary_sim/ContactPoint.h"
#include "catenary_sim/hil/rig_pantograph.hpp"

namespace catenary_sim {
namespace ros_layer {

using hil::RigPantograph;
using hil::RigStepper;
using hil::WirePoint;

// The wire points of one pantograph's hil/contact_point entry.
std::vector<WirePoint> wire_points(const ContactPoint& c);

}  // namespace ros_layer
}  // namespace catenary_sim
