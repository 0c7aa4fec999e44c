// Reading a scene's YAML tree into a Scene, room by room: the line and its tension sections here,
// the pantographs, the 3-D line's rooms and the imperfections in the files beside it. Every field
// is read strictly (scene_reader.hpp): a value out of range or an unknown key is an error naming it.
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "catenary_sim/core/output/zero_phase_filter.hpp"
#include "scene/read_imperfections.hpp"
#include "scene/read_lateral_scene.hpp"
#include "scene/read_pantographs.hpp"
#include "scene/scene_reader.hpp"

namespace catenary_sim {

using namespace scene_reading;
namespace {

WireSpec read_wire(Reader& r) {
  WireSpec w;
  w.linear_mass = r.number("linear_mass", 0.0, 100.0, std::nullopt, true);
  w.bending_stiffness = r.number("bending_stiffness", 0.0, 1e6, 0.0);
  w.tension = r.number("tension", 0.0, 1e6, std::nullopt, true);
  return w;
}

SupportSpec read_support(Reader& r) {
  SupportSpec s;
  s.stiffness = r.number("stiffness", 0.0, 1e10, std::nullopt, true);
  s.mass = r.number("mass", 0.0, 1000.0, 0.0);
  r.finish();
  return s;
}

// Steady arms: a spring of eq. 4 (`stiffness`, `mass`), or a hinged arm as built (`length`,
// `linear_mass`, `clamp_mass`, `pull_off`) whose k_A and tip mass follow from it.
SupportSpec read_steady_arms(Reader& r, const std::string& path) {
  // Any of the arm's own fields makes it a hinged arm, so that a missing length is named as such.
  const char* arm_field = nullptr;
  for (const char* k : {"length", "linear_mass", "clamp_mass", "pull_off"})
    if (!arm_field && r.has(k)) arm_field = k;
  if (!arm_field) return read_support(r);
  for (const char* spring : {"stiffness", "mass"})
    if (r.has(spring))
      fail(path + "." + spring, std::string("(given with ") + arm_field + ")",
           "either a spring (stiffness, mass) or a hinged arm (length, linear_mass, clamp_mass, pull_off), not both: "
           "a hinged arm's stiffness and mass follow from its geometry and pull-off");
  HingedArmSpec a;
  // At least 0.1 m: registration arms are 0.3-1.5 m; a shorter one's k_A = pull_off / length
  // (eq. 4) runs to infinity, and its inclination flips under the uplift.
  a.length = r.number("length", 0.1, 5.0, std::nullopt);
  a.linear_mass = r.number("linear_mass", 0.0, 20.0, std::nullopt);
  a.clamp_mass = r.number("clamp_mass", 0.0, 20.0, 0.0);
  if (r.has("pull_off")) a.pull_off = r.number("pull_off", 0.0, 1e5, std::nullopt, true);
  r.finish();
  SupportSpec s;
  s.mass = a.tip_mass();
  s.hinged_arm = a;
  return s;
}

void read_spans(Reader& r, const std::string& path, std::vector<double>& spans) {
  if (r.has("spans")) {
    if (r.has("span_length") || r.has("span_count"))
      fail(path + ".spans", "(given with span_length/span_count)", "give either spans or span_length and span_count");
    spans = r.numbers("spans", 0.5, 500.0);
  } else {
    const double len = r.number("span_length", 0.5, 500.0);
    const double count = r.number("span_count", 1.0, 10000.0);
    if (count != std::floor(count)) fail(path + ".span_count", fmt(count), "a whole number >= 1");
    spans.assign(static_cast<std::size_t>(count), len);
  }
  if (spans.empty()) fail(path + ".spans", "[]", "at least one span");
}

// The wire, dropper and support parts of a section (or the scene's defaults when defaults is null).
// conductor_rail: the profile with its clamped contact wire as one beam without tension (paper
// Benet et al. 2021, Eqs. 5-6: EI of the equivalent section), on elastic supports. It stands for
// contact_wire and steady_arms; a messenger, droppers or presag have nothing to act on.
void read_conductor_rail(Reader& r, const std::string& pre, SectionSpec& sec) {
  for (const char* other : {"contact_wire", "messenger", "droppers", "steady_arms", "messenger_supports", "stitch_wire",
                            "contact_wire_count", "auxiliary_messenger", "hangers", "bridle"})
    if (r.has(other))
      fail(pre + other, "(given with conductor_rail)",
           "a rigid conductor rail has no tensioned wires, droppers or steady arms: give conductor_rail alone "
           "(its support_stiffness and support_mass hold the profile)");
  Reader c(r.child("conductor_rail"), pre + "conductor_rail");
  sec.rigid = true;
  sec.contact_wire = ContactWireSpec{};
  sec.contact_wire.linear_mass = c.number("linear_mass", 0.0, 100.0, std::nullopt, true);
  sec.contact_wire.bending_stiffness = c.number("bending_stiffness", 0.0, kMaxRailBendingStiffness, std::nullopt, true);
  if (c.has("lateral_bending_stiffness"))
    sec.rail_lateral_bending_stiffness = c.number("lateral_bending_stiffness", 0.0, kMaxRailBendingStiffness, std::nullopt, true);
  if (c.has("transition_piece")) {
    Reader t(c.child("transition_piece"), pre + "conductor_rail.transition_piece");
    SectionSpec::TransitionPiece piece;
    piece.length = t.number("length", 0.0, 500.0, std::nullopt, true);  // (within the end span: validate_rigid)
    piece.end_bending_stiffness = t.number("end_bending_stiffness", 0.0, kMaxRailBendingStiffness, std::nullopt, true);
    t.finish();
    sec.rail_transition_piece = piece;
  }
  SupportSpec support;
  support.stiffness = c.number("support_stiffness", 0.0, 1e10, std::nullopt, true);
  support.mass = c.number("support_mass", 0.0, 1000.0, 0.0);
  c.finish();
  sec.steady_arms = support;
  sec.messenger.reset();
  sec.droppers.reset();
  sec.messenger_supports.reset();
  sec.auxiliary_messenger.reset();
  sec.hangers.reset();
  sec.bridle.reset();
  sec.stitch_wire.reset();
  sec.contact_wire_count = 1;
}

// A section's stitch wire; `stitch_wire: none` in a section leaves out the one the scene's
// defaults give (a simple section, e.g. in a tunnel, on a stitched line).
void read_stitch_wire(Reader& r, const std::string& pre, SectionSpec& sec) {
  const YAML::Node node = r.child("stitch_wire");
  if (node.IsScalar()) {
    if (node.Scalar() != "none")
      fail(pre + "stitch_wire", node.Scalar(), "a map of length, tension, linear_mass, ... or none (no stitch wire)");
    sec.stitch_wire.reset();
    return;
  }
  Reader w(r.child("stitch_wire"), pre + "stitch_wire");
  StitchWireSpec st;
  if (w.has("lengths")) {
    if (w.has("length"))
      fail(w.field("length"), "(given with lengths)", "one of them: length for every support, or lengths, one per support that carries one");
    st.lengths = w.numbers("lengths", 0.0, 100.0, true);
    if (st.lengths.empty()) fail(w.field("lengths"), "[]", "one length (m, > 0) per support that carries a stitch wire");
  } else {
    st.length = w.number("length", 0.0, 100.0, std::nullopt, true);
  }
  st.tension = w.number("tension", 0.0, 1e5, std::nullopt, true);
  st.linear_mass = w.number("linear_mass", 0.0, 10.0, std::nullopt, true);
  st.bending_stiffness = w.number("bending_stiffness", 0.0, 1e4, 0.0);
  st.clamp_mass = w.number("clamp_mass", 0.0, 10.0, 0.0);
  if (w.has("at_supports")) {
    const std::vector<double> at = w.numbers("at_supports", 1.0, 1e6);
    const std::string f = w.field("at_supports");
    if (at.empty()) fail(f, "[]", "the intermediate supports (1, 2, ...) that carry one; stitch_wire: none for no stitch wire");
    for (std::size_t i = 0; i < at.size(); ++i) {
      if (at[i] != std::floor(at[i])) fail(f + "[" + std::to_string(i) + "]", fmt(at[i]), "a whole support number (1: after the first span)");
      if (i > 0 && !(at[i] > at[i - 1]))
        fail(f + "[" + std::to_string(i) + "]", fmt(at[i]), "above " + fmt(at[i - 1]) + ": support numbers in increasing order, each once");
      st.at_supports.push_back(static_cast<int>(at[i]));
    }
  }
  w.finish();
  sec.stitch_wire = st;
}

// A section's bridles; `bridle: none` in a section leaves out the ones the scene's defaults give.
void read_bridle(Reader& r, const std::string& pre, SectionSpec& sec) {
  const YAML::Node node = r.child("bridle");
  if (node.IsScalar()) {
    if (node.Scalar() != "none") fail(pre + "bridle", node.Scalar(), "a map of length, tension, linear_mass, ... or none (no bridle)");
    sec.bridle.reset();
    return;
  }
  Reader w(node, pre + "bridle");
  BridleSpec b;
  b.length = w.number("length", 0.0, 100.0, std::nullopt, true);
  b.tension = w.number("tension", 0.0, 1e5, std::nullopt, true);
  b.linear_mass = w.number("linear_mass", 0.0, 10.0, std::nullopt, true);
  b.bending_stiffness = w.number("bending_stiffness", 0.0, 1e4, 0.0);
  b.clamp_mass = w.number("clamp_mass", 0.0, 10.0, 0.0);
  w.finish();
  sec.bridle = b;
}

// Droppers, or a compound line's hangers (the same parts between the auxiliary messenger and the
// contact wire): their positions in each span and what they are made of.
DropperSpec read_droppers(Reader& r, const std::string& f, const std::string& key) {
  Reader d(r.child(key), f);
  DropperSpec ds;
  if (d.has("positions") == d.has("positions_per_span"))
    fail(f + ".positions", "(both or neither given)", "give positions (same in every span) or positions_per_span");
  if (d.has("positions")) {
    ds.positions.assign(1, d.numbers("positions", 0.0, 500.0, true));  // expanded per span later
    if (ds.positions.front().empty())
      fail(f + ".positions", "[]", "at least one position in m from the span start (or remove the " + key + " section)");
  } else {
    const YAML::Node per = d.child("positions_per_span");
    if (!per.IsSequence()) fail(f + ".positions_per_span", "(not a list)", "one list of positions per span");
    for (std::size_t i = 0; i < per.size(); ++i) {
      std::vector<double> v;
      const std::string fi = f + ".positions_per_span[" + std::to_string(i) + "]";
      if (!per[i].IsSequence()) fail(fi, "(not a list)", "a list of positions in m");
      for (std::size_t j = 0; j < per[i].size(); ++j)
        v.push_back(Reader::parse_number(per[i][j], fi + "[" + std::to_string(j) + "]", 0.0, 500.0, true));
      ds.positions.push_back(v);
    }
    ds.per_span = true;
    std::size_t count = 0;
    for (const auto& v : ds.positions) count += v.size();
    if (count == 0)
      fail(f + ".positions_per_span", "(none in any span)", "at least one position (or remove the " + key + " section)");
  }
  if (d.has("transition_positions")) ds.transition_positions = d.numbers("transition_positions", 0.0, 500.0, true);
  ds.axial_stiffness = d.number("axial_stiffness", 0.0, 1e10, std::nullopt, true);
  ds.linear_mass = d.number("linear_mass", 0.0, 10.0, 0.0);
  ds.clamp_mass_contact = d.number("clamp_mass_contact", 0.0, 100.0, 0.0);
  // (A hanger's upper clamp is on the auxiliary messenger.)
  ds.clamp_mass_messenger = d.number(key == "hangers" ? "clamp_mass_auxiliary" : "clamp_mass_messenger", 0.0, 100.0, 0.0);
  d.finish();
  return ds;
}

// A compound catenary's auxiliary messenger: a tensioned wire and its height above the contact
// wire at the droppers; `auxiliary_messenger: none` in a section leaves out the scene's.
void read_auxiliary_messenger(Reader& r, const std::string& pre, SectionSpec& sec) {
  const YAML::Node node = r.child("auxiliary_messenger");
  if (node.IsScalar()) {
    if (node.Scalar() != "none")
      fail(pre + "auxiliary_messenger", node.Scalar(), "a map of linear_mass, tension, height, ... or none (a simple catenary)");
    // (A section's own hangers beside `none` contradict it; the scene's, e.g. left out by
    // `--set auxiliary_messenger=none`, go with the auxiliary.)
    if (!pre.empty() && r.has("hangers"))
      fail(pre + "hangers", "(given with auxiliary_messenger: none)", "no hangers: they hang from the auxiliary messenger");
    sec.auxiliary_messenger.reset();
    sec.hangers.reset();
    return;
  }
  Reader w(node, pre + "auxiliary_messenger");
  AuxiliaryMessengerSpec aux;
  static_cast<WireSpec&>(aux) = read_wire(w);
  aux.height = w.number("height", 0.0, 10.0, std::nullopt, true);
  w.finish();
  sec.auxiliary_messenger = aux;
}

void read_section_parts(Reader& r, const std::string& path, SectionSpec& sec, const SectionSpec* defaults) {
  const std::string pre = path.empty() ? "" : path + ".";
  if (r.has("conductor_rail")) {
    read_conductor_rail(r, pre, sec);
    return;
  }
  // A rail section by the top level's conductor_rail takes none of a catenary's parts; its own
  // contact_wire makes it a catenary section.
  if (sec.rigid && !r.has("contact_wire"))
    for (const char* other : {"messenger", "droppers", "steady_arms", "messenger_supports", "stitch_wire",
                              "contact_wire_count", "auxiliary_messenger", "hangers", "bridle"})
      if (r.has(other))
        fail(pre + other, "(given in a section of the top level's conductor_rail)",
             "a rigid conductor rail has no tensioned wires, droppers or steady arms (its support_stiffness and "
             "support_mass hold the profile); give the section a contact_wire to make it a catenary section");
  if (r.has("contact_wire") && sec.rigid) {  // a catenary section among rigid defaults: none of the rail's parts
    SectionSpec fresh;
    fresh.spans = sec.spans;
    sec = fresh;
  }
  if (r.has("contact_wire")) {
    Reader w(r.child("contact_wire"), pre + "contact_wire");
    static_cast<WireSpec&>(sec.contact_wire) = read_wire(w);
    sec.contact_wire.presag = w.number("presag", -1.0, 1.0, 0.0);
    w.finish();
  } else if (!defaults) {
    fail("contact_wire", "(missing)", "required section");
  }
  if (r.has("messenger")) {
    Reader w(r.child("messenger"), pre + "messenger");
    sec.messenger = read_wire(w);
    w.finish();
  }
  if (r.has("droppers")) sec.droppers = read_droppers(r, pre + "droppers", "droppers");
  if (r.has("hangers")) sec.hangers = read_droppers(r, pre + "hangers", "hangers");
  if (r.has("auxiliary_messenger")) read_auxiliary_messenger(r, pre, sec);
  if (r.has("steady_arms")) {
    Reader a(r.child("steady_arms"), pre + "steady_arms");
    sec.steady_arms = read_steady_arms(a, pre + "steady_arms");
  }
  if (r.has("messenger_supports")) {
    Reader a(r.child("messenger_supports"), pre + "messenger_supports");
    if (a.has("length"))
      fail(pre + "messenger_supports.length", "(given)",
           "a messenger support is a spring (stiffness, mass); hinged arms (length, ...) are steady_arms'");
    sec.messenger_supports = read_support(a);
  }
  if (r.has("stitch_wire")) read_stitch_wire(r, pre, sec);
  if (r.has("bridle")) read_bridle(r, pre, sec);
}

// Section stations from the overlaps, dropper positions per span, and the line's spans (the union
// of every section's supports).
void resolve_line(Scene& s) {
  const int k = s.overlap ? s.overlap->spans : 0;
  std::vector<double> supports;
  for (std::size_t i = 0; i < s.sections.size(); ++i) {
    SectionSpec& sec = s.sections[i];
    const std::string path = s.sections.size() > 1 ? "sections[" + std::to_string(i) + "]" : "line";
    if (i > 0) {
      const SectionSpec& prev = s.sections[i - 1];
      if (static_cast<int>(prev.spans.size()) < k || static_cast<int>(sec.spans.size()) < k)
        fail(path + ".spans", std::to_string(sec.spans.size()) + " spans",
             "at least overlap.spans (" + std::to_string(k) + ") in every section");
      for (int j = 0; j < k; ++j) {
        const double a = prev.spans[prev.spans.size() - k + j], b = sec.spans[j];
        if (std::fabs(a - b) > 1e-9)
          fail(path + ".spans[" + std::to_string(j) + "]", fmt(b),
               "equal to the overlapping span of the previous section (" + fmt(a) + " m)");
      }
      double st = prev.start;
      for (std::size_t j = 0; j + k < prev.spans.size(); ++j) st += prev.spans[j];
      sec.start = st;
    }
    for (auto [part, key] : {std::pair{&sec.droppers, "droppers"}, std::pair{&sec.hangers, "hangers"}}) {
      if (!*part) continue;
      DropperSpec& d = **part;
      const std::size_t n = sec.spans.size();
      if (d.per_span) {
        if (d.positions.size() != n)
          fail(s.section_field(i, std::string(key) + ".positions_per_span"), "(" + std::to_string(d.positions.size()) + " entries)",
               "one list per span (" + std::to_string(n) + ")");
      } else {
        const std::vector<double> common = d.positions.empty() ? std::vector<double>{} : d.positions.front();
        d.positions.assign(n, common);
        if (!d.transition_positions.empty() && s.sections.size() < 2)
          fail(std::string(key) + ".transition_positions", "(given on a line of one section)",
               "only where tension sections overlap (two or more): their transition spans take them; remove it here");
        if (!d.transition_positions.empty()) {
          if (sec.last_span_transition) d.positions[n - 1] = d.transition_positions;
          if (sec.first_span_transition) {
            std::vector<double> mirrored;
            for (auto it = d.transition_positions.rbegin(); it != d.transition_positions.rend(); ++it)
              mirrored.push_back(sec.spans[0] - *it);
            d.positions[0] = mirrored;
          }
        }
      }
    }
    double x = sec.start;
    supports.push_back(x);
    for (double l : sec.spans) supports.push_back(x += l);
  }
  std::sort(supports.begin(), supports.end());
  s.spans.clear();
  for (std::size_t i = 1; i < supports.size(); ++i)
    if (supports[i] - supports[i - 1] > 1e-9) s.spans.push_back(supports[i] - supports[i - 1]);
  if (!s.sections.empty()) s.droppers = s.sections.front().droppers;
}

// line: the heights, the spans (or an endless line's one span), and the tension sections.
void read_line(Reader& top, Scene& s) {
  Reader r(top.child("line"), "line");
  if (!top.has("line")) fail("line", "(missing)", "required section with spans (or span_length and span_count)");
  s.contact_wire_height = r.number("contact_wire_height", 0.0, 100.0, 5.3);
  s.encumbrance = r.number("encumbrance", 0.0, 10.0, 1.2, true);
  const bool has_sections = top.has("sections");
  if (has_sections && (r.has("spans") || r.has("span_length") || r.has("span_count")))
    fail("line.spans", "(given with sections)", "with sections, every section gives its own spans");
  SectionSpec defaults;
  s.endless = r.boolean("endless", false);
  if (s.endless) {
    if (has_sections) fail("line.endless", "true", "a single tension section (remove the sections list)");
    if (r.has("spans") || r.has("span_count"))
      fail(r.has("spans") ? "line.spans" : "line.span_count", "(given with endless: true)",
           "an endless line repeats one span: give span_length only");
    defaults.spans.assign(1, r.number("span_length", 0.5, 500.0));
  } else if (!has_sections) {
    read_spans(r, "line", defaults.spans);
  }
  read_section_parts(top, "", defaults, nullptr);
  if (!has_sections) {
    defaults.contact_wire_count = 1;
    s.sections.push_back(defaults);
  } else {
    const YAML::Node secs = top.child("sections");
    if (!secs.IsSequence() || secs.size() == 0) fail("sections", "(not a non-empty list)", "a list of tension sections");
    for (std::size_t i = 0; i < secs.size(); ++i) {
      const std::string path = "sections[" + std::to_string(i) + "]";
      Reader sr(secs[i], path);
      SectionSpec sec = defaults;
      if (secs[i].IsMap())
        for (const auto& kv : secs[i]) sec.given.push_back(kv.first.Scalar());
      read_spans(sr, path, sec.spans);
      read_section_parts(sr, path, sec, &defaults);
      const double count = sr.number("contact_wire_count", 1.0, 2.0, 1.0);
      if (count != std::floor(count)) fail(sr.field("contact_wire_count"), fmt(count), "1 or 2 (twin contact wire)");
      sec.contact_wire_count = static_cast<int>(count);
      sec.first_span_transition = sr.boolean("first_span_transition", i > 0);
      sec.last_span_transition = sr.boolean("last_span_transition", i + 1 < secs.size());
      sr.finish();
      s.sections.push_back(sec);
    }
  }
  r.finish();
}

void read_overlap(Reader& top, Scene& s) {
  if (top.has("overlap")) {
    Reader r(top.child("overlap"), "overlap");
    OverlapSpec o;
    const double k = r.number("spans", 1.0, 10.0, 1.0);
    if (k != std::floor(k)) fail("overlap.spans", fmt(k), "a whole number of transition spans >= 1");
    o.spans = static_cast<int>(k);
    if (r.has("support_rise")) o.support_rise = r.number("support_rise", 0.0, 2.0);
    if (r.has("design_force")) o.design_force = r.number("design_force", 0.0, 2000.0, std::nullopt, true);
    o.lateral_separation = r.number("lateral_separation", -1.0, 1.0, 0.0);
    r.finish();
    if (s.sections.size() < 2)
      fail("overlap", "(given on a line of one section)",
           "only where tension sections overlap (sections: two or more); remove it here");
    s.overlap = o;
  } else if (s.sections.size() > 1) {
    s.overlap = OverlapSpec{};
  }
}

void read_damping(Reader& top, Scene& s) {
  if (top.has("damping")) {
    Reader r(top.child("damping"), "damping");
    s.rayleigh_alpha = r.number("alpha", 0.0, 100.0, 0.0);
    s.rayleigh_beta = r.number("beta", 0.0, 0.1, 0.0);
    r.finish();
  }
}

void read_contact(Reader& top, Scene& s) {
  if (top.has("contact")) {
    Reader r(top.child("contact"), "contact");
    s.contact.stiffness = r.number("stiffness", 0.0, 1e9, 50000.0, true);
    s.contact.rub_length = r.number("rub_length", 0.0, 5.0, 0.0);
    r.finish();
  }
}

void read_train(Reader& top, Scene& s) {
  if (top.has("train")) {
    Reader r(top.child("train"), "train");
    if (r.has("speed") && r.has("speed_kmh")) fail("train.speed", "(given with speed_kmh)", "give either speed (m/s) or speed_kmh");
    // Any finite speed here; validate() refuses what is outside the limit, 0 up to below the wave
    // speed, with that range (train_speed_limit). What is not a finite number is refused with the
    // same words, the wave speed being the sections' to set.
    auto speed = [&](const char* key, const char* unit, double per_m_s) {
      const YAML::Node n = r.child(key);
      try {
        return Reader::parse_number(n, r.field(key), -kInf, kInf, false);
      } catch (const SceneError&) {
        fail(r.field(key), n.IsScalar() ? "'" + n.Scalar() + "'" : "(not a scalar)",
             std::string("a number in ") + unit + ", from 0 to below the contact wire's wave speed, at most " +
                 fmt(kMaxTrainSpeed * per_m_s));
      }
    };
    if (r.has("speed_kmh")) s.train_speed = speed("speed_kmh", "km/h", 3.6) / 3.6;
    else if (r.has("speed")) s.train_speed = speed("speed", "m/s", 1.0);
    // Stations in m, finite (within a million km: a line's, not a bound anything reaches).
    if (r.has("start")) s.train_start = r.number("start", -1e9, 1e9);
    if (r.has("end")) s.train_end = r.number("end", -1e9, 1e9);
    r.finish();
  }
}

// numerics.window: auto, off, or {ahead, behind}.
void read_window(Reader& r, Scene& s) {
  if (!r.has("window")) return;
  const YAML::Node wn = r.child("window");
  if (wn.IsScalar() && wn.as<std::string>() == "auto") {
    s.numerics.window_auto = true;  // lengths from speed and wave speed: window_lengths()
  } else if (wn.IsScalar() && wn.as<std::string>() == "off") {
  } else {
    Reader w(wn, "numerics.window");
    s.numerics.window_ahead = w.number("ahead", 0.0, 1e5, std::nullopt, true);
    s.numerics.window_behind = w.number("behind", 0.0, 1e5, std::nullopt, true);
    w.finish();
  }
}

// numerics.gust_lead: auto, or seconds of travel.
void read_gust_lead(Reader& r, Scene& s) {
  if (!r.has("gust_lead")) return;
  const YAML::Node n = r.child("gust_lead");
  const std::string raw = n.IsScalar() ? n.as<std::string>() : "(not a scalar)";
  if (raw != "auto") {
    double v = std::nan("");
    if (n.IsScalar()) {
      try {
        v = n.as<double>();
      } catch (const YAML::Exception&) {
      }
    }
    if (!(v >= 0.0 && v <= kMaxGustLead))
      fail("numerics.gust_lead", raw, "auto, or seconds of travel in [0, " + fmt(kMaxGustLead) + "]");
    s.numerics.gust_lead = v;
  }
}

// numerics.gust_lead_step: implicit or explicit (absent: auto, LeadStep).
void read_gust_lead_step(Reader& r, Scene& s) {
  if (!r.has("gust_lead_step")) return;
  const std::string v = r.text("gust_lead_step", "");
  if (v == "implicit") s.numerics.gust_lead_step = LeadStep::kImplicit;
  else if (v == "explicit") s.numerics.gust_lead_step = LeadStep::kExplicit;
  else
    fail("numerics.gust_lead_step", "'" + v + "'",
         "one of: implicit (the lead on its own, the trapezoidal rule at the wind's refresh interval), explicit (with "
         "the lateral window, at its dt)");
}

// numerics: the fidelity ladder. Returns whether the reference preset's own element length and
// damping apply (neither given); `springs_by_preset`: the supports' and the droppers' step, each
// whether the fast preset chose it (not given).
bool read_numerics(Reader& top, Scene& s, std::pair<bool, bool>* springs_by_preset) {
  bool reference_defaults = false;
  if (!top.has("numerics")) return reference_defaults;
  Reader r(top.child("numerics"), "numerics");
  // A preset sets the defaults of the fidelity ladder; every field can still be set on its own.
  const std::string preset = r.text("preset", "");
  double h = 0.25;
  // Element lengths measured in bench/speed_accuracy (BENCHMARKS.md): all explicit, because on
  // these lines the condensed explicit scheme is the fastest at every accuracy level. The
  // reference rung chosen in bench_reference_rung against h = 0.03125 m: h = 0.0625 m with the
  // centred damping keeps every statistic within 0.05 % of that finer solution, its dt the
  // undamped limit (with the half-step damping, the stiffness-proportional damping of the
  // shortest mesh modes cut it 2.6x; where the centred step does not go, h = 0.1 m below).
  if (preset == "fast") {
    h = 1.0;
  } else if (preset == "balanced") {
    h = 0.5;
  } else if (preset == "accurate" || preset.empty()) {
    h = 0.25;
  } else if (preset == "reference") {
    h = 0.0625;
  } else {
    fail("numerics.preset", "'" + preset + "'", "one of: fast, balanced, accurate, reference");
  }
  s.numerics.preset = preset;
  reference_defaults = preset == "reference" && !r.has("element_length") && !r.has("damping");
  s.numerics.element_length = r.number("element_length", 0.01, 10.0, h);
  if (r.has("dt")) {
    const YAML::Node n = r.child("dt");
    if (!(n.IsScalar() && n.as<std::string>() == "auto"))
      s.numerics.dt = Reader::parse_number(n, "numerics.dt", 0.0, 0.1, true);
  }
  s.numerics.safety_factor = r.number("safety_factor", 0.0, 1.0, 0.9, true);
  const std::string integ = r.text("integrator", "explicit");
  if (integ == "explicit") s.numerics.integrator = Integrator::kExplicit;
  else if (integ == "implicit") s.numerics.integrator = Integrator::kImplicit;
  else fail("numerics.integrator", "'" + integ + "'", "one of: explicit (central differences, eq. 19-21), implicit (Newmark average acceleration)");
  const std::string rt = r.text("rotary_inertia", s.numerics.integrator == Integrator::kImplicit ? "lumped" : "condensed");
  if (rt == "condensed") s.numerics.rotary_inertia = RotaryInertia::kCondensed;
  else if (rt == "lumped") s.numerics.rotary_inertia = RotaryInertia::kLumped;
  else fail("numerics.rotary_inertia", "'" + rt + "'", "one of: condensed (massless rotations, statically condensed), lumped (HRZ rotary inertia)");
  if (s.numerics.integrator == Integrator::kImplicit && s.numerics.rotary_inertia == RotaryInertia::kCondensed)
    fail("numerics.rotary_inertia", "'condensed'", "lumped with the implicit integrator (its matrix holds the rotations as DOFs)");
  const std::string dmp = r.text("damping", preset == "reference" ? "centred" : "half_step");
  if (dmp == "half_step") s.numerics.damping = DampingStep::kHalfStep;
  else if (dmp == "centred") s.numerics.damping = DampingStep::kCentred;
  else fail("numerics.damping", "'" + dmp + "'", "one of: half_step (C v at v_{n-1/2}, eq. 19-21), centred (C v at (v_{n+1/2} + v_{n-1/2}) / 2)");
  // The supports' springs and the droppers at the step's middle, where the explicit half-step runs
  // (explicit_step.cpp).
  const bool middle_allowed = s.numerics.integrator == Integrator::kExplicit && s.numerics.damping == DampingStep::kHalfStep;
  // The fast rung takes them at the middle by default (where the scheme allows it, on a 2-D line:
  // scene_from_yaml): its dt is then set by the wires' 1 m elements instead of the supports' and
  // droppers' springs on light nodes.
  const bool middle_default = preset == "fast" && middle_allowed;
  *springs_by_preset = {middle_default && !r.has("supports"), middle_default && !r.has("droppers")};
  auto spring_step = [&](const char* key) {
    const std::string field = std::string("numerics.") + key;
    const std::string v = r.text(key, middle_default ? "implicit" : "explicit");
    SpringStep step = SpringStep::kExplicit;
    if (v == "implicit") step = SpringStep::kImplicit;
    else if (v != "explicit")
      fail(field, "'" + v + "'", "one of: explicit (at q_n, eq. 19-21), implicit (at the step's middle, the trapezoidal rule)");
    if (step == SpringStep::kImplicit && !middle_allowed)
      fail(field, "'implicit'",
           s.numerics.integrator != Integrator::kExplicit
               ? "explicit with the implicit integrator (its matrix holds every spring already)"
               : "explicit with numerics.damping centred (the springs at the step's middle go with the half-step damping)");
    return step;
  };
  s.numerics.supports = spring_step("supports");
  s.numerics.droppers = spring_step("droppers");
  s.numerics.divergence_limit = r.number("divergence_limit", 0.0, 1000.0, 5.0, true);
  s.numerics.allow_supercritical = r.boolean("allow_supercritical", false);
  read_window(r, s);
  read_gust_lead(r, s);
  read_gust_lead_step(r, s);
  r.finish();
  return reference_defaults;
}

void read_output(Reader& top, Scene& s) {
  if (top.has("output")) {
    Reader r(top.child("output"), "output");
    if (r.has("analysis_spans")) {
      const std::vector<double> a = r.numbers("analysis_spans", 0.0, 1e6);
      if (a.size() != 2 || a[0] != std::floor(a[0]) || a[1] != std::floor(a[1]))
        fail("output.analysis_spans", "(" + std::to_string(a.size()) + " values)", "two whole span indices [first, last)");
      s.output.analysis_first_span = static_cast<int>(a[0]);
      s.output.analysis_last_span = static_cast<int>(a[1]);
    }
    s.output.filter_cutoff = r.number("filter_cutoff", kLeastFilterCutoff, 10000.0, 20.0);
    s.output.sample_rate = r.number("sample_rate", 0.0, 1e6, 0.0);
    s.output.sensor_bandwidth = r.number("sensor_bandwidth", kLeastFilterCutoff, 10000.0, 20.0);
    s.output.dropper_series = r.boolean("dropper_series", false);
    auto optional_number = [&](const char* key, double lo, double hi, bool lo_open) -> std::optional<double> {
      if (!r.has(key)) return std::nullopt;
      return r.number(key, lo, hi, std::nullopt, lo_open);
    };
    s.output.allowed_uplift = optional_number("allowed_uplift", 0.0, 10.0, true);
    s.output.max_stat_force = optional_number("max_stat_force", 0.0, 1e5, true);
    s.output.min_stat_force = optional_number("min_stat_force", -1e5, 1e5, false);
    s.output.max_contact_loss_percent = optional_number("max_contact_loss_percent", 0.0, 100.0, false);
    r.finish();
  }
}

}  // namespace

Scene scene_from_yaml(const YAML::Node& root, const std::string& base_dir) {
  bool reference_defaults = false;  // preset reference, element length and damping its own
  if (!root || !root.IsMap()) throw SceneError("scene: the document must be a YAML map of sections (line, contact_wire, ...)");
  Reader top(root, "");
  Scene s;
  s.name = top.text("name", "scene");
  s.gravity = top.number("gravity", 0.0, 100.0, 9.81);
  read_line(top, s);
  read_overlap(top, s);
  // The first section's parts stay available as the scene's defaults.
  const SectionSpec& first = s.sections.front();
  s.contact_wire = first.contact_wire;
  s.messenger = first.messenger;
  s.droppers = first.droppers;
  s.steady_arms = first.steady_arms;
  s.messenger_supports = first.messenger_supports;
  s.stitch_wire = first.stitch_wire;
  s.bridle = first.bridle;
  s.auxiliary_messenger = first.auxiliary_messenger;
  s.hangers = first.hangers;
  resolve_line(s);
  read_damping(top, s);
  read_contact(top, s);
  read_pantographs(top, s);
  read_train(top, s);
  std::pair<bool, bool> springs_by_preset;  // the supports' and droppers' step chosen by the fast preset
  reference_defaults = read_numerics(top, s, &springs_by_preset);
  read_imperfections(top, s, base_dir);
  read_output(top, s);
  read_lateral_parts(top, s);
  top.finish();
  // A 3-D line's fast rung keeps its supports and droppers at q_n: its droppers cannot go to the
  // middle (validate_scene.cpp), and the supports alone there move its dropper forces further from
  // the finer rungs' (BENCHMARKS.md, the fidelity ladder). The preset's default needs the whole
  // scene to know the line is 3-D.
  if (s.lateral() && springs_by_preset.first) s.numerics.supports = SpringStep::kExplicit;
  if (s.lateral() && springs_by_preset.second) s.numerics.droppers = SpringStep::kExplicit;
  // The reference rung's centred damping steps the explicit scheme with beta > 0
  // (NumericsSpec::damping); elsewhere the rung is h = 0.1 m with the half-step damping, the finest
  // its explicit dt allows at a reference's cost (docs/benchmark_history.md, "Choosing the
  // reference rung").
  if (reference_defaults && (!(s.rayleigh_beta > 0.0) ||
                             s.numerics.integrator != Integrator::kExplicit ||
                             s.numerics.rotary_inertia != RotaryInertia::kCondensed)) {
    s.numerics.element_length = 0.1;
    s.numerics.damping = DampingStep::kHalfStep;
  }
  // On a finite line one radius is one curve over the whole line (heading from station 0).
  if (!s.endless && s.alignment.radius != 0.0) {
    s.alignment.curves = {CurveSpec{0.0, s.line_length(), s.alignment.radius, 0.0}};
    s.alignment.radius = 0.0;
  }
  validate(s);
  return s;
}

}  // namespace catenary_sim
