#include "catenary_sim/ros/replay.hpp"

#include "catenary_sim/core/model/lateral.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace catenary_sim {
namespace ros_layer {

namespace {

std::string num(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

const char* const kOtherScene = " (is ~scene the scene of the recording?)";

// Height of the recorded samples at station x: linear between samples, the end sample beyond.
double interpolate(const std::vector<double>& xs, const std::vector<double>& ys, double x) {
  if (x <= xs.front()) return ys.front();
  if (x >= xs.back()) return ys.back();
  const std::size_t k = std::upper_bound(xs.begin(), xs.end(), x) - xs.begin();  // xs[k-1] <= x < xs[k]
  const double t = (x - xs[k - 1]) / (xs[k] - xs[k - 1]);
  return ys[k - 1] + t * (ys[k] - ys[k - 1]);
}

// Wires: same names in the same order, each sampled over the stations of the scene's wire; the
// wires' displacements, lateral positions (3-D line) and the line offset.
std::string wires_from_shape(const Model& m, const WireShapeArray& shape, State* s) {
  if (shape.wires.size() != m.wires.size())
    return "wire_shape has " + num(shape.wires.size()) + " wires, the scene " + num(m.wires.size()) + kOtherScene;
  double offset = 0.0;
  for (std::size_t wi = 0; wi < m.wires.size(); ++wi) {
    const Wire& w = m.wires[wi];
    const WireShape& ws = shape.wires[wi];
    const std::string field = "wire_shape.wires[" + num(wi) + "]";
    if (ws.name != w.name) return field + ".name = '" + ws.name + "': expected '" + w.name + "'" + kOtherScene;
    if (ws.stations.empty() || ws.stations.size() != ws.heights.size())
      return field + ": " + num(ws.stations.size()) + " stations and " + num(ws.heights.size()) +
             " heights: expected as many of each, at least one";
    for (std::size_t k = 0; k < ws.stations.size(); ++k)
      if (!std::isfinite(ws.stations[k]) || !std::isfinite(ws.heights[k]) || (k > 0 && !(ws.stations[k] > ws.stations[k - 1])))
        return field + ".stations/heights[" + num(k) + "] = " + num(ws.stations[k]) + " / " + num(ws.heights[k]) +
               ": expected finite values at increasing stations";
    // Stations along the line are the model's plus the line offset (endless line), the same for every wire.
    const double o = ws.stations.front() - w.x.front();
    const double length = ws.stations.back() - ws.stations.front(), expected = w.x.back() - w.x.front();
    if (std::fabs(length - expected) > 1e-6)
      return field + " ('" + w.name + "') spans " + num(length) + " m: the scene's wire spans " + num(expected) + " m" +
             kOtherScene;
    if (wi == 0) offset = o;
    else if (std::fabs(o - offset) > 1e-6)
      return field + ".stations[0] = " + num(ws.stations.front()) + ": expected " + num(w.x.front() + offset) +
             " (the line offset of the first wire)" + kOtherScene;
    // A pass stops where a displacement passes numerics.divergence_limit: a recorded height
    // further from the design is not a pass's (1 cm over it: the design read between nodes).
    const double limit = m.scene.numerics.divergence_limit + 0.01;
    for (std::size_t k = 0; k < ws.stations.size(); ++k) {
      const double design = interpolate(w.x, w.height, ws.stations[k] - o);
      if (!(std::fabs(ws.heights[k] - design) <= limit))
        return field + ".heights[" + num(k) + "] = " + num(ws.heights[k]) + " m at station " + num(ws.stations[k]) +
               " m: expected within numerics.divergence_limit (" + num(m.scene.numerics.divergence_limit) +
               " m) of the design height " + num(design) + " m";
    }
    for (int i = 0; i < w.nodes(); ++i)
      s->wire_uplift(m, static_cast<int>(wi), i) = interpolate(ws.stations, ws.heights, w.x[i] + o) - w.height[i];
    // A 3-D line's lateral positions (an empty list on a 2-D line).
    const std::size_t lateral_expected = m.lateral ? ws.stations.size() : 0;
    if (ws.lateral.size() != lateral_expected)
      return field + ".lateral has " + num(ws.lateral.size()) + " values: expected " + num(lateral_expected) +
             (m.lateral ? " (one per station: the scene is a 3-D line)" : " (the scene is a 2-D line)") + kOtherScene;
    for (std::size_t k = 0; k < ws.lateral.size(); ++k)
      if (!std::isfinite(ws.lateral[k]))
        return field + ".lateral[" + num(k) + "] = " + num(ws.lateral[k]) + ": expected a finite value, m";
    if (m.lateral && s->lateral.y.size() == m.lateral->n)
      for (int i = 0; i < w.nodes(); ++i)
        s->lateral.y[m.lateral->wires[wi].w_dof + i] = interpolate(ws.stations, ws.lateral, w.x[i] + o);
  }
  s->line_offset = offset;
  return "";
}

// Train and pantographs: the kinematics, the masses, the uplift and the contact forces (after the
// wires: the train front is on the line offset they set).
std::string train_from_messages(const Model& m, const PantographStateArray& state, const ContactForceArray& force,
                                State* s) {
  const double offset = s->line_offset;
  if (state.pantographs.size() != m.pantographs.size())
    return "pantograph_state has " + num(state.pantographs.size()) + " pantographs, the scene " +
           num(m.pantographs.size()) + kOtherScene;
  if (force.pantographs.size() != m.pantographs.size())
    return "contact_force has " + num(force.pantographs.size()) + " pantographs, the scene " +
           num(m.pantographs.size()) + kOtherScene;
  // Every number drawn or read again must be finite: a NaN in a recording is refused by name, as
  // the wires' samples are, never drawn.
  for (const auto& [name, v] : {std::pair<const char*, double>{"sim_time", state.sim_time}, {"train_front", state.train_front},
                                {"speed", state.speed}, {"target_speed", state.target_speed},
                                {"max_acceleration", state.max_acceleration}})
    if (!std::isfinite(v)) return std::string("pantograph_state.") + name + " = " + num(v) + ": expected a finite value";
  s->time = state.sim_time;
  s->steps = state.step;
  s->front = state.train_front - offset;
  s->speed = state.speed;
  s->target_speed = state.target_speed;
  s->max_acceleration = state.max_acceleration;
  const std::size_t nw = m.contact_wires.size();
  for (std::size_t p = 0; p < m.pantographs.size(); ++p) {
    const Pantograph& pg = m.pantographs[p];
    const PantographState& ps = state.pantographs[p];
    const ContactForce& c = force.pantographs[p];
    const std::string field = "pantograph_state.pantographs[" + num(p) + "]";
    if (ps.name != pg.name) return field + ".name = '" + ps.name + "': expected '" + pg.name + "'" + kOtherScene;
    if (c.name != pg.name)
      return "contact_force.pantographs[" + num(p) + "].name = '" + c.name + "': expected '" + pg.name + "'" + kOtherScene;
    const std::size_t masses = pg.moving_force ? 0 : static_cast<std::size_t>(pg.dof_count());  // chain, then heads
    if (ps.displacement.size() != masses || ps.velocity.size() != masses)
      return field + ": " + num(ps.displacement.size()) + " displacements and " + num(ps.velocity.size()) +
             " velocities: expected " + num(masses) + " of each (the masses of '" + pg.name + "')" + kOtherScene;
    for (std::size_t i = 0; i < masses; ++i) {
      if (!std::isfinite(ps.displacement[i]) || !std::isfinite(ps.velocity[i]))
        return field + ".displacement/velocity[" + num(i) + "] = " + num(ps.displacement[i]) + " / " + num(ps.velocity[i]) +
               ": expected finite values";
      s->pantograph_displacement(m, static_cast<int>(p), static_cast<int>(i)) = ps.displacement[i];
      s->pantograph_velocity(m, static_cast<int>(p), static_cast<int>(i)) = ps.velocity[i];
    }
    if (!std::isfinite(ps.uplift)) return field + ".uplift = " + num(ps.uplift) + ": expected a finite value, N";
    s->uplift[p] = ps.uplift;
    if (c.contact_wires.size() != nw)
      return "contact_force.pantographs[" + num(p) + "].contact_wires has " + num(c.contact_wires.size()) +
             " names, the scene " + num(nw) + " contact wires" + kOtherScene;
    for (std::size_t k = 0; k < nw; ++k)
      if (c.contact_wires[k] != m.wires[m.contact_wires[k]].name)
        return "contact_force.pantographs[" + num(p) + "].contact_wires[" + num(k) + "] = '" + c.contact_wires[k] +
               "': expected '" + m.wires[m.contact_wires[k]].name + "'" + kOtherScene;
    if (c.wire_forces.size() != pg.collectors.size() * nw)
      return "contact_force.pantographs[" + num(p) + "].wire_forces has " + num(c.wire_forces.size()) +
             " values: expected " + num(pg.collectors.size() * nw) + " (collectors x contact wires)" + kOtherScene;
    for (std::size_t j = 0; j < pg.collectors.size(); ++j)
      for (std::size_t k = 0; k < nw; ++k) {
        const double f = c.wire_forces[j * nw + k];  // message: collectors x wires
        if (!std::isfinite(f))
          return "contact_force.pantographs[" + num(p) + "].wire_forces[" + num(j * nw + k) + "] = " + num(f) +
                 ": expected a finite value, N";
        s->contact_force_on(m, pg.collectors[j], static_cast<int>(k)) = f;
      }
  }
  return "";
}

// Droppers: slack where the core's criterion says so (no tension at the elastic stretch, on a
// 3-D line with the lean's share from the recorded lateral positions: lateral.hpp); on a 3-D line
// the contact points across the strips and the sway.
void droppers_and_contact_points(const Model& m, State* s) {
  const bool leaning = m.lateral && s->lateral.y.size() == m.lateral->n && !s->lateral.dropper_stretch.empty();
  if (leaning) set_dropper_stretch(m, *s);
  for (std::size_t d = 0; d < m.droppers.size(); ++d) {
    const Dropper& dr = m.droppers[d];
    double stretch = s->u[dr.messenger_dof] - s->u[dr.contact_dof];
    if (leaning) stretch += s->lateral.dropper_stretch[d];
    s->dropper_slack[d] = !(dr.static_tension + dr.stiffness * stretch > 0.0);
  }
  if (m.lateral && s->lateral.y.size() == m.lateral->n) lateral_observe(m, *s);  // the contact points across the strips and the sway (3-D line)
}

}  // namespace

std::string state_from_messages(const Model& m, const WireShapeArray& shape, const PantographStateArray& state,
                                const ContactForceArray& force, State* s) {
  if (std::string e = wires_from_shape(m, shape, s); !e.empty()) return e;
  if (std::string e = train_from_messages(m, state, force, s); !e.empty()) return e;
  droppers_and_contact_points(m, s);
  return "";
}

std::string scene_difference(const Model& given, const Model& recorded) {
  // Stations to 1 um: both built by the same code from the same numbers. Heights to 1 cm: the
  // meshes may differ (the recording's preset, a finer replay), and the same design solved on 1 m
  // and on 0.25 m elements differs by about a millimetre (measured: 1.1 mm on a bridle of
  // the reference trolley wire, 1.2 mm on the compound line's messenger), read linearly
  // between the recording's nodes; what the scene's design fields move is tens of centimetres
  // and more (an auxiliary's height, a bridle's V).
  constexpr double kSameStation = 1e-6, kSameHeight = 1e-2;
  if (given.support_x.size() != recorded.support_x.size())
    return "the scene has " + num(given.support_x.size()) + " supports, the recording's " + num(recorded.support_x.size());
  for (std::size_t k = 0; k < given.support_x.size(); ++k)
    if (std::fabs(given.support_x[k] - recorded.support_x[k]) > kSameStation)
      return "support " + num(k) + " is at " + num(given.support_x[k]) + " m, in the recording's scene at " +
             num(recorded.support_x[k]) + " m";
  if (given.wires.size() != recorded.wires.size())
    return "the scene has " + num(given.wires.size()) + " wires, the recording's " + num(recorded.wires.size());
  for (std::size_t wi = 0; wi < given.wires.size(); ++wi) {
    const Wire &a = given.wires[wi], &b = recorded.wires[wi];
    if (a.name != b.name) return "wire " + num(wi) + " is '" + a.name + "', in the recording's scene '" + b.name + "'";
    if (std::fabs(a.x.front() - b.x.front()) > kSameStation || std::fabs(a.x.back() - b.x.back()) > kSameStation)
      return "wire '" + a.name + "' runs " + num(a.x.front()) + "-" + num(a.x.back()) + " m, in the recording's scene " +
             num(b.x.front()) + "-" + num(b.x.back()) + " m";
    for (std::size_t i = 0; i < a.x.size(); ++i) {
      const double there = interpolate(b.x, b.height, a.x[i]);
      if (std::fabs(a.height[i] - there) > kSameHeight)
        return "wire '" + a.name + "' at station " + num(a.x[i]) + " m is designed at " + num(a.height[i]) +
               " m, in the recording's scene at " + num(there) + " m";
    }
  }
  if (given.droppers.size() != recorded.droppers.size())
    return "the scene has " + num(given.droppers.size()) + " droppers, the recording's " + num(recorded.droppers.size());
  return "";
}

}  // namespace ros_layer
}  // namespace catenary_sim
