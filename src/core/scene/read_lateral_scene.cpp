#include "scene/read_lateral_scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

namespace catenary_sim {

using namespace scene_reading;
namespace {

std::uint64_t read_seed(Reader& r, const std::string& key) {
  const double v = r.number(key, 0.0, 9007199254740992.0, 0.0);
  if (v != std::floor(v)) fail(r.field(key), fmt(v), "a whole number >= 0");
  return static_cast<std::uint64_t>(v);
}

void read_stagger(Reader& top, Scene& s) {
  if (!top.has("stagger")) return;
  Reader r(top.child("stagger"), "stagger");
  StaggerSpec st;
  st.contact_wire = r.numbers("contact_wire", -1.0, 1.0);
  if (st.contact_wire.empty()) fail("stagger.contact_wire", "(empty list)", "at least one offset, m");
  if (r.has("messenger")) {
    st.messenger = r.numbers("messenger", -1.0, 1.0);
    // An empty list reads as "no offsets": neither the contact wire's (what the field's absence
    // gives) nor 0 is what it says, so it is asked for explicitly.
    if (st.messenger.empty())
      fail("stagger.messenger", "(empty list)",
           "at least one offset, m ([0.0]: the messenger above the track centre); leave the field out for the "
           "messenger above the contact wire (its stagger)");
  }
  st.per_support = r.boolean("per_support", false);
  if (r.has("steady_arm_stiffness")) st.steady_arm_stiffness = r.number("steady_arm_stiffness", 0.0, 1e9, std::nullopt, true);
  if (r.has("messenger_support_stiffness"))
    st.messenger_support_stiffness = r.number("messenger_support_stiffness", 0.0, 1e9, std::nullopt, true);
  r.finish();
  s.stagger = st;
}

void read_alignment(Reader& top, Scene& s) {
  if (!top.has("alignment")) return;
  Reader r(top.child("alignment"), "alignment");
  if (r.has("radius")) {
    // The whole line on one radius: what an endless line can repeat (every span alike).
    if (r.has("curves"))
      fail("alignment.radius", "(given with alignment.curves)", "one of the two: curves placed by station, or radius for the whole line");
    s.alignment.radius = r.number("radius", -1e6, 1e6);
    if (std::fabs(s.alignment.radius) < 100.0)
      fail("alignment.radius", fmt(s.alignment.radius), "|radius| of at least 100 m (+ to the left, - to the right)");
  }
  const YAML::Node cs = r.has("radius") ? YAML::Node(YAML::NodeType::Sequence) : r.child("curves");
  if (!cs || !cs.IsSequence())
    fail("alignment.curves", "(missing or not a list)", "a list of {start, length, radius[, transition]}, or alignment.radius");
  for (std::size_t i = 0; i < cs.size(); ++i) {
    Reader q(cs[i], "alignment.curves[" + std::to_string(i) + "]");
    CurveSpec c;
    c.start = q.number("start", 0.0, 1e7);
    c.length = q.number("length", 0.0, 1e6, std::nullopt, true);
    // Wires are chords between supports; the small-angle lateral plane needs radius >> span.
    c.radius = q.number("radius", -1e6, 1e6);
    if (std::fabs(c.radius) < 100.0)
      fail(q.field("radius"), fmt(c.radius), "|radius| of at least 100 m (+ to the left, - to the right)");
    c.transition = q.number("transition", 0.0, 1e6, 0.0);
    if (2.0 * c.transition > c.length)
      fail(q.field("transition"), fmt(c.transition), "at most half the curve's length (" + fmt(0.5 * c.length) + " m)");
    if (i > 0 && c.start < s.alignment.curves.back().start + s.alignment.curves.back().length)
      fail(q.field("start"), fmt(c.start), "after the end of the previous curve (" +
           fmt(s.alignment.curves.back().start + s.alignment.curves.back().length) + " m)");
    q.finish();
    s.alignment.curves.push_back(c);
  }
  r.finish();
}

void read_wind(Reader& top, Scene& s) {
  if (!top.has("wind")) return;
  Reader r(top.child("wind"), "wind");
  WindSpec w;
  w.speed = r.number("speed", 0.0, 70.0);
  w.direction = r.number("direction", -360.0, 360.0, 90.0);
  w.air_density = r.number("air_density", 0.0, 2.0, 1.225, true);
  // A wire's width is its diameter; a rail's profile meets the wind with its height.
  auto drag = [&](const char* key, WireDragSpec& d, const char* width = "diameter", double widest = 0.1) {
    if (!r.has(key)) return;
    Reader q(r.child(key), std::string("wind.") + key);
    d.diameter = q.number(width, 0.0, widest, d.diameter, true);
    d.drag_coefficient = q.number("drag_coefficient", 0.0, 3.0, d.drag_coefficient);
    q.finish();
    w.drag_given.emplace_back(key);
  };
  drag("contact_wire", w.contact_wire);
  drag("messenger", w.messenger);
  drag("stitch_wire", w.stitch_wire);
  drag("auxiliary_messenger", w.auxiliary_messenger);
  drag("bridle", w.bridle);
  drag("conductor_rail", w.conductor_rail, "height", 0.5);
  if (r.has("turbulence")) {
    Reader q(r.child("turbulence"), "wind.turbulence");
    TurbulenceSpec t;
    t.intensity = q.number("intensity", 0.0, 0.5, std::nullopt, true);
    t.length_scale = q.number("length_scale", 0.0, 1000.0, 50.0, true);
    t.coherence_decay = q.number("coherence_decay", 0.0, 100.0, 10.0, true);
    t.max_frequency = q.number("max_frequency", 0.0, 50.0, 5.0, true);
    t.spacing = q.number("spacing", 0.0, 100.0, 5.0, true);
    t.seed = read_seed(q, "seed");
    q.finish();
    if (!(w.speed > 0.0)) fail("wind.speed", fmt(w.speed), "above 0 with wind.turbulence (its spectrum scales with the mean speed)");
    w.turbulence = t;
  }
  if (r.has("blow_off_limit")) w.blow_off_limit = r.number("blow_off_limit", 0.0, 10.0, std::nullopt, true);
  r.finish();
  s.wind = w;
}

void read_pantograph_head(Reader& top, Scene& s) {
  if (!top.has("pantograph_head")) return;
  Reader r(top.child("pantograph_head"), "pantograph_head");
  PantographHeadSpec& h = s.pantograph_head;
  h.working_width = r.number("working_width", 0.0, 5.0, 1.2, true);
  h.horn_width = r.number("horn_width", 0.0, 5.0, std::max(1.95, h.working_width), true);
  if (h.horn_width < h.working_width)
    fail("pantograph_head.horn_width", fmt(h.horn_width), "at least the working width (" + fmt(h.working_width) + " m)");
  const std::string act = r.text("on_dewirement", "continue");
  if (act == "continue") h.on_dewirement = DewirementAction::kContinue;
  else if (act == "stop") h.on_dewirement = DewirementAction::kStop;
  else fail("pantograph_head.on_dewirement", "'" + act + "'", "one of: continue (record and go on), stop (end the pass)");
  if (r.has("sway")) {
    Reader q(r.child("sway"), "pantograph_head.sway");
    if (q.has("times") || q.has("lateral")) {
      // A measured sway: samples in time (a car body's lateral motion at the pantograph).
      if (q.has("amplitude") || q.has("frequency"))
        fail("pantograph_head.sway", "(amplitude/frequency and times/lateral)", "one of: {amplitude, frequency} or {times, lateral}");
      h.sway_times = q.numbers("times", 0.0, 1e6);
      h.sway_lateral = q.numbers("lateral", -1.0, 1.0);
      if (h.sway_times.empty()) fail("pantograph_head.sway.times", "(empty list)", "at least one time, s");
      if (h.sway_lateral.size() != h.sway_times.size())
        fail("pantograph_head.sway.lateral", "(" + std::to_string(h.sway_lateral.size()) + " values)",
             "one per time of pantograph_head.sway.times (" + std::to_string(h.sway_times.size()) + ")");
      for (std::size_t i = 1; i < h.sway_times.size(); ++i)
        if (!(h.sway_times[i] > h.sway_times[i - 1]))
          fail("pantograph_head.sway.times[" + std::to_string(i) + "]", fmt(h.sway_times[i]),
               "after the time before it (" + fmt(h.sway_times[i - 1]) + " s): increasing times");
    } else {
      h.sway_amplitude = q.number("amplitude", 0.0, 1.0);
      h.sway_frequency = q.number("frequency", 0.0, 20.0);
    }
    q.finish();
  }
  h.histogram_bin = r.number("histogram_bin", 0.0, 1.0, 0.02, true);
  r.finish();
}

}  // namespace

void read_lateral_parts(Reader& top, Scene& s) {
  read_stagger(top, s);
  read_alignment(top, s);
  read_wind(top, s);
  read_pantograph_head(top, s);
}

}  // namespace catenary_sim
