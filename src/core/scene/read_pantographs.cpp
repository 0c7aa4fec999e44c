#include "scene/read_pantographs.hpp"

#include <cmath>
#include <string>
#include <vector>

namespace catenary_sim {

using namespace scene_reading;
namespace {

// target_mean_force: the mean contact force Fm(v) = a v^2 + b the pantograph is set against.
TargetMeanForce read_target_mean_force(Reader& r) {
  const YAML::Node t = r.child("target_mean_force");
  Reader tr(t, r.field("target_mean_force"));
  TargetMeanForce target;
  const std::string unit = tr.text("speed_unit", "m/s");
  if (unit != "m/s" && unit != "km/h")
    fail(tr.field("speed_unit"), "'" + unit + "'", "m/s or km/h (the unit of v in Fm(v) = a v^2 + b)");
  target.speed_kmh = unit == "km/h";
  // a: up to 1 N s^2/m^2 (1/12.96 of that per (km/h)^2), about 10 times EN 50367's curves.
  target.a = tr.number("a", 0.0, target.speed_kmh ? 1.0 / 12.96 : 1.0);
  target.b = tr.number("b", 0.0, 2000.0);
  if (tr.has("tolerance")) target.tolerance = tr.number("tolerance", 0.0, 2000.0);
  tr.finish();
  return target;
}

// The chain of lumped masses (head first, the last spring to the roof); none for a moving force.
void read_mass_chain(Reader& r, const std::string& type, PantographSpec& p) {
  if (!p.moving_force) {
    p.masses = r.numbers("masses", 0.0, 1000.0, true);
    p.stiffness = r.numbers("stiffness", 0.0, 1e8);
    p.damping = r.has("damping") ? r.numbers("damping", 0.0, 1e6) : std::vector<double>(p.masses.size(), 0.0);
    if (p.masses.empty()) fail(r.field("masses"), "[]", "at least one mass (the head first)");
    if (p.stiffness.size() != p.masses.size())
      fail(r.field("stiffness"), std::to_string(p.stiffness.size()) + " values",
           "one per mass (" + std::to_string(p.masses.size()) + "): the spring below each mass, the last to the roof");
    if (p.damping.size() != p.masses.size())
      fail(r.field("damping"), std::to_string(p.damping.size()) + " values",
           "one per mass (" + std::to_string(p.masses.size()) + ")");
    for (std::size_t i = 0; i + 1 < p.stiffness.size(); ++i)
      if (p.stiffness[i] <= 0.0)
        fail(r.field("stiffness") + "[" + std::to_string(i) + "]", fmt(p.stiffness[i]),
             "must be > 0 between two masses (only the last, to the roof, may be 0)");
  } else {
    for (const char* k : {"masses", "stiffness", "damping"})
      if (r.has(k)) fail(r.field(k), "(given)", "not allowed for type " + type + " (it has no masses)");
  }
}

// A pantograph's (or a head's) carbon strips; one strip at offset 0 when none are given.
void read_collectors(Reader& r, std::vector<CollectorSpec>& out) {
  if (!r.has("collectors")) {
    out.push_back(CollectorSpec{});
    return;
  }
  const YAML::Node cs = r.child("collectors");
  if (!cs.IsSequence() || cs.size() == 0) fail(r.field("collectors"), "(not a non-empty list)", "a list of {offset: m, working_width: m}");
  for (std::size_t i = 0; i < cs.size(); ++i) {
    Reader c(cs[i], r.field("collectors") + "[" + std::to_string(i) + "]");
    CollectorSpec col;
    col.offset = c.number("offset", -5.0, 5.0, 0.0);
    if (c.has("working_width")) col.working_width = c.number("working_width", 0.0, 5.0, std::nullopt, true);
    c.finish();
    out.push_back(col);
  }
}

// Heads, each a mass on its own suspension to the chain's top mass, with their strips.
void read_heads(Reader& r, const std::string& type, PantographSpec& p) {
  if (p.moving_force) fail(r.field("heads"), "(given)", "not allowed for type " + type + " (it has no masses)");
  if (r.has("collectors"))
    fail(r.field("collectors"), "(given with heads)", "collectors on the heads (heads[i].collectors) when heads are given");
  const YAML::Node hs = r.child("heads");
  if (!hs.IsSequence() || hs.size() == 0) fail(r.field("heads"), "(not a non-empty list)", "a list of heads");
  for (std::size_t i = 0; i < hs.size(); ++i) {
    Reader h(hs[i], r.field("heads") + "[" + std::to_string(i) + "]");
    HeadSpec head;
    head.mass = h.number("mass", 0.0, 1000.0, std::nullopt, true);
    if (!h.has("stiffness"))
      fail(h.field("stiffness"), "(missing)", "a suspension spring > 0 N/m to the top frame mass (a head without "
                                              "suspension is the chain's first mass: give no heads)");
    head.stiffness = h.number("stiffness", 0.0, 1e8, std::nullopt, true);
    head.damping = h.number("damping", 0.0, 1e6, 0.0);
    head.offset = h.number("offset", -5.0, 5.0, 0.0);
    head.length = h.number("length", 0.0, 5.0, 0.5, true);
    head.aero_coefficient = h.number("aero_coefficient", -1.0, 1.0, 0.0);
    if (h.has("aero_coefficient_trailing")) head.aero_coefficient_trailing = h.number("aero_coefficient_trailing", -1.0, 1.0);
    read_collectors(h, head.collectors);
    for (std::size_t c = 0; c < head.collectors.size(); ++c)
      if (std::fabs(head.collectors[c].offset) > 0.5 * head.length + 1e-12)
        fail(h.field("collectors") + "[" + std::to_string(c) + "].offset", fmt(head.collectors[c].offset),
             "within the head: |offset| <= length / 2 = " + fmt(0.5 * head.length) + " m from its centre");
    h.finish();
    p.heads.push_back(head);
  }
}

PantographSpec read_pantograph(const YAML::Node& node, const std::string& path, std::size_t index) {
  Reader r(node, path);
  PantographSpec p;
  p.name = r.text("name", "pantograph_" + std::to_string(index));
  p.position = r.number("position", 0.0, 10000.0, 0.0);
  const std::string type = r.text("type", "lumped");
  if (type == "lumped") {
    p.moving_force = false;
  } else if (type == "moving_force") {
    p.moving_force = true;
  } else if (type == "external") {
    p.moving_force = true;
    p.external = true;
  } else {
    fail(r.field("type"), "'" + type + "'", "one of: lumped, moving_force, external (hardware in the loop)");
  }
  p.static_uplift = r.number("static_uplift", 0.0, 2000.0);
  p.aero_coefficient = r.number("aero_coefficient", -1.0, 1.0, 0.0);
  if (r.has("aero_coefficient_trailing")) p.aero_coefficient_trailing = r.number("aero_coefficient_trailing", -1.0, 1.0);
  const std::string knee = r.text("knee", "leading");
  if (knee != "leading" && knee != "trailing")
    fail(r.field("knee"), "'" + knee + "'", "leading or trailing (the frame's knee in the direction of travel)");
  p.knee_trailing = knee == "trailing";
  if (r.has("target_mean_force")) p.target_mean_force = read_target_mean_force(r);
  read_mass_chain(r, type, p);
  if (r.has("heads")) {
    read_heads(r, type, p);
  } else {
    read_collectors(r, p.collectors);
  }
  r.finish();
  return p;
}

}  // namespace

void read_pantographs(Reader& top, Scene& s) {
  if (top.has("pantographs")) {
    const YAML::Node ps = top.child("pantographs");
    if (!ps.IsSequence()) fail("pantographs", "(not a list)", "a list of pantographs");
    for (std::size_t i = 0; i < ps.size(); ++i)
      s.pantographs.push_back(read_pantograph(ps[i], "pantographs[" + std::to_string(i) + "]", i));
  }
}

}  // namespace catenary_sim
