#include "catenary_sim/ros/virtual_rig.hpp"

namespace catenary_sim {
namespace ros_layer {

std::vector<WirePoint> wire_points(const ContactPoint& c) {
  std::vector<WirePoint> p(c.on_wire.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    p[i].on_wire = c.on_wire[i];
    p[i].height = c.wire_height[i];
    p[i].path_velocity = c.wire_path_velocity[i];
  }
  return p;
}

}  // namespace ros_layer
}  // namespace catenary_sim
