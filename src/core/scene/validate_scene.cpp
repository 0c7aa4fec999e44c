// The scene's cross-field checks (validate): what each field alone allows is the reader's; here
// what the fields allow together, each refusal naming a field, its value and what is allowed.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <set>
#include <string>

#include "scene/scene_reader.hpp"
#include "util/format_limit.hpp"

namespace catenary_sim {

using namespace scene_reading;
namespace {

// Where section i's spans were given: its entry in `sections` (spans, or span_length and
// span_count), or the line's.
std::string spans_field(const Scene& s, std::size_t i) {
  const std::vector<std::string>& given = s.sections[i].given;
  const auto gives = [&](const char* k) { return std::find(given.begin(), given.end(), k) != given.end(); };
  if (gives("spans")) return "sections[" + std::to_string(i) + "].spans";
  if (gives("span_count")) return "sections[" + std::to_string(i) + "].span_count";
  return "line.spans";
}

// The largest sag under q per metre of a simply supported span whose EI rises linearly from
// end_ei at one end to ei at `length` from it (a rail's transition piece), ei beyond: the
// curvature M / EI, M = q x (span - x) / 2, integrated twice (trapezoids; 2000 steps put the
// uniform span's 5 q L^4 / (384 EI) within 1e-6 of itself).
double softened_span_sag(double q, double span, double ei, double end_ei, double length) {
  constexpr int kSteps = 2000;
  const double h = span / kSteps;
  auto curvature = [&](double x) {
    const double e = x < length ? end_ei + (ei - end_ei) * x / length : ei;
    return q * x * (span - x) / (2.0 * e);
  };
  // g'' = M / EI with g(0) = g'(0) = 0; the sag is the chord's height above g: x g(L) / L - g(x).
  std::vector<double> g(kSteps + 1, 0.0);
  double slope = 0.0, k0 = curvature(0.0);
  for (int j = 1; j <= kSteps; ++j) {
    const double k1 = curvature(j * h), before = slope;
    slope += 0.5 * h * (k0 + k1);
    g[j] = g[j - 1] + 0.5 * h * (before + slope);
    k0 = k1;
  }
  double sag = 0.0;
  for (int j = 0; j <= kSteps; ++j) sag = std::max(sag, g[kSteps] * j / kSteps - g[j]);
  return sag;
}

// What makes a line 3-D (Scene::lateral()), as refusals name it.
constexpr const char* kLateralFields = "stagger, alignment, wind or pantograph_head.sway";
const std::string kOnlyOnThreeD = std::string("only on a 3-D line (") + kLateralFields + ")";

// Every section's droppers hang from its messenger, inside their spans, in order.
void validate_sections(const Scene& s) {
  if (s.sections.empty()) fail("line", "(no tension section)", "at least one section of spans");
  // Droppers and hangers hang the wires below them by their weight: without it they carry nothing
  // and the design statics cannot set the presag.
  if (s.gravity == 0.0)
    for (std::size_t si = 0; si < s.sections.size(); ++si)
      if (s.sections[si].droppers)
        fail("gravity", "0", "> 0 m/s^2 on a line with droppers (they hang the contact wire by its weight)");
  for (std::size_t si = 0; si < s.sections.size(); ++si) {
    const SectionSpec& sec = s.sections[si];
    const auto in_section = [&](const std::string& name) { return s.section_field(si, name); };
    if (sec.rigid) {
      // The rail's beam carries no tension: anything hung from a messenger, a presag set by
      // droppers or a support-less profile has no meaning here.
      if (sec.messenger || sec.droppers || sec.messenger_supports || sec.contact_wire_count != 1)
        fail(in_section("conductor_rail"), "(with a messenger, droppers or a twin wire)",
             "a rigid conductor rail alone: remove messenger, droppers, messenger_supports, contact_wire_count");
      if (!sec.steady_arms || !(sec.steady_arms->stiffness > 0.0))
        fail(in_section("conductor_rail.support_stiffness"), "(missing)", "> 0 N/m at every support");
      if (sec.contact_wire.tension != 0.0 || sec.contact_wire.presag != 0.0)
        fail(in_section("conductor_rail"), "(tension or presag set)", "tension 0 and presag 0: the profile is not tensioned");
      if (!(sec.contact_wire.bending_stiffness > 0.0))
        fail(in_section("conductor_rail.bending_stiffness"), fmt(sec.contact_wire.bending_stiffness), "> 0 N m^2");
      if (sec.spans.size() < 2)
        fail(spans_field(s, si), std::to_string(sec.spans.size()) + " span",
             "at least 2 spans in a rigid section (its ends are held, its intermediate supports are elastic)");
      continue;
    }
    if (!(sec.contact_wire.tension > 0.0))
      fail(in_section("contact_wire.tension"), fmt(sec.contact_wire.tension), "> 0 N (a tensioned wire; a profile without tension is a conductor_rail)");
    if (sec.droppers && !sec.messenger)
      fail(in_section("droppers"), "(given)", "droppers hang the contact wire from a messenger: add a messenger section or remove droppers");
    if (sec.messenger_supports && !sec.messenger) fail(in_section("messenger_supports"), "(given)", "needs a messenger section");
    if (sec.contact_wire_count == 2 && !sec.droppers)
      fail(in_section("contact_wire_count"), "2", "a twin contact wire hangs from droppers: add droppers and a messenger");
    if (sec.contact_wire.presag != 0.0 && !sec.droppers)
      fail(in_section("contact_wire.presag"), fmt(sec.contact_wire.presag), "0 without droppers (the presag is set by the dropper lengths)");
    if (sec.steady_arms && sec.steady_arms->hinged_arm) {
      const std::optional<double>& pull_off = sec.steady_arms->hinged_arm->pull_off;
      if (s.lateral() && pull_off)
        fail(in_section("steady_arms.pull_off"), fmt(*pull_off) + " (on a 3-D line)",
             "not given on a 3-D line: there each arm's pull-off comes from the stagger and the curves (remove it)");
      if (!s.lateral() && !pull_off)
        fail(in_section("steady_arms.pull_off"), "(missing)",
             "required on a 2-D line, N > 0: the wire's horizontal pull on the arm (4 T s / L for a zigzag of +-s on "
             "straight track, + T L / R on a curve)");
    }
    for (auto [part, key] : {std::pair{&sec.droppers, "droppers"}, std::pair{&sec.hangers, "hangers"}}) {
      if (!*part) continue;
      const DropperSpec& d = **part;
      if (d.positions.size() != sec.spans.size())
        fail(in_section(key + std::string(".positions_per_span")), std::to_string(d.positions.size()) + " lists", "one per span");
      for (std::size_t i = 0; i < sec.spans.size(); ++i) {
        const auto& p = d.positions[i];
        for (std::size_t j = 0; j < p.size(); ++j) {
          const std::string f = in_section(key + std::string(".positions (span ")) + std::to_string(i) + ", position " + std::to_string(j) + ")";
          if (p[j] <= 0.0 || p[j] >= sec.spans[i])
            fail(f, fmt(p[j]), "strictly inside the span (0, " + fmt(sec.spans[i]) + ") m");
          if (j > 0 && p[j] <= p[j - 1]) fail(f, fmt(p[j]), "increasing along the span (previous " + fmt(p[j - 1]) + ")");
        }
      }
    }
  }
}

// The train speed, and the limits on what a pass allocates or on the centred step's dt.
void validate_limits(const Scene& s) {
  const TrainSpeedLimit speed = train_speed_limit(s);
  if (!speed.allows(s.train_speed)) {
    const double v = s.train_speed;
    std::string value = fmt(v * 3.6) + " (" + fmt(v) + " m/s";
    if (v >= speed.wave_speed) value += ", " + fmt4(v / speed.wave_speed) + " times the contact wire's wave speed";
    fail("train.speed_kmh", value + ")", "allowed " + speed.text());
  }
  {
    const PantographHeadSpec& h = s.pantograph_head;
    if (!(h.histogram_bin > 0.0) || h.horn_width / h.histogram_bin > kMaxHistogramBins)
      fail("pantograph_head.histogram_bin", fmt(h.histogram_bin),
           "allowed [" + fmt4(h.horn_width / kMaxHistogramBins) + ", 1] m: at most " + fmt(kMaxHistogramBins) +
               " bins across pantograph_head.horn_width = " + fmt(h.horn_width) + " m");
  }
  if (s.wind && s.wind->turbulence) {
    const double points = wind_field_points(s);
    if (!(points <= kMaxWindFieldPoints)) {
      const double spacing = s.wind->turbulence->spacing, reach = (points - 1.0) * spacing;
      fail("wind.turbulence.spacing", fmt(spacing),
           "allowed [" + fmt4(reach / (kMaxWindFieldPoints - 1.0)) + ", 100] m here: at most " + fmt(kMaxWindFieldPoints) +
               " field points over the " + fmt4(reach) + " m of line the field holds at once (this spacing gives " + fmt4(points) +
                   ")");
    }
  }
  if (s.numerics.damping == DampingStep::kCentred && s.numerics.safety_factor > kCentredMaxSafetyFactor)
    fail("numerics.safety_factor", fmt(s.numerics.safety_factor),
         "at most " + fmt(kCentredMaxSafetyFactor) + " with numerics.damping: centred (its stability estimate is no bound "
         "at the estimate itself; half_step takes up to 1)");
}

// Fields that could never act in this scene are refused rather than silently ignored.
void validate_acting_fields(const Scene& s) {
  if (s.numerics.gust_lead && !(s.wind && s.wind->turbulence && s.numerics.windowed()))
    fail("numerics.gust_lead", fmt(*s.numerics.gust_lead),
         "only with a turbulent wind (wind.turbulence) and the moving window (numerics.window): it is how much further "
         "ahead of the vertical window the lateral plane is stepped; remove it here");
  if (s.numerics.gust_lead_step) {
    const std::string v = *s.numerics.gust_lead_step == LeadStep::kImplicit ? "'implicit'" : "'explicit'";
    if (!(s.wind && s.wind->turbulence && s.numerics.windowed()))
      fail("numerics.gust_lead_step", v,
           "only with a turbulent wind (wind.turbulence) and the moving window (numerics.window), where the lateral "
           "plane has a gust lead; remove it here");
    bool stitched = false;
    for (const SectionSpec& sec : s.sections) stitched |= sec.stitch_wire.has_value();
    if (stitched && *s.numerics.gust_lead_step == LeadStep::kImplicit)
      fail("numerics.gust_lead_step", v,
           "explicit on a line with stitch wires (their stiff clamps join the messenger's and the stitch wire's "
           "solves, which the implicit lead takes one wire at a time)");
  }
  if (!s.lateral())
    for (std::size_t i = 0; i < s.sections.size(); ++i)
      if (s.sections[i].rail_lateral_bending_stiffness)
        fail(s.section_field(i, "conductor_rail.lateral_bending_stiffness"),
             fmt(*s.sections[i].rail_lateral_bending_stiffness),
             kOnlyOnThreeD + ": a 2-D line does not bend the "
             "profile across the track");
  if (s.stagger && std::none_of(s.sections.begin(), s.sections.end(), [](const SectionSpec& sec) { return sec.messenger.has_value(); })) {
    // A messenger's stagger or support on a line without one would hold nothing.
    const std::string allowed = "absent: no section has a messenger (a trolley wire or a rail); remove it";
    if (!s.stagger->messenger.empty()) fail("stagger.messenger", "(given)", allowed);
    if (s.stagger->messenger_support_stiffness)
      fail("stagger.messenger_support_stiffness", fmt(*s.stagger->messenger_support_stiffness), allowed);
  }
  if (s.wind) {
    // A drag block for a wire the line does not have would load nothing.
    auto has = [&](const std::string& kind) {
      return std::any_of(s.sections.begin(), s.sections.end(), [&](const SectionSpec& sec) {
        if (kind == "conductor_rail") return sec.rigid;
        if (kind == "contact_wire") return !sec.rigid;
        if (kind == "messenger") return sec.messenger.has_value();
        if (kind == "stitch_wire") return sec.stitch_wire.has_value();
        if (kind == "bridle") return sec.bridle.has_value();
        return sec.auxiliary_messenger.has_value();
      });
    };
    for (const std::string& kind : s.wind->drag_given)
      if (!has(kind))
        fail("wind." + kind, "(given)",
             "a drag block for a wire the line has: no section has " +
                 (kind == "contact_wire" ? std::string("a tensioned contact wire (a rail's profile takes wind.conductor_rail)")
                                         : kind == "conductor_rail" ? std::string("a conductor_rail (a tensioned contact wire takes wind.contact_wire)")
                                                                    : "a " + kind) +
                 "; remove it here");
  }
  if (!s.lateral() && s.overlap && s.overlap->lateral_separation != 0.0)
    fail("overlap.lateral_separation", fmt(s.overlap->lateral_separation),
         "0 on a 2-D line, or a 3-D line (" + std::string(kLateralFields) + ") that has the wires' "
         "positions in plan");
  if (!s.lateral())
    for (std::size_t i = 0; i < s.pantographs.size(); ++i) {
      const PantographSpec& p = s.pantographs[i];
      auto check = [&](const std::vector<CollectorSpec>& cs, const std::string& field) {
        for (std::size_t j = 0; j < cs.size(); ++j)
          if (cs[j].working_width)
            fail(field + "[" + std::to_string(j) + "].working_width", fmt(*cs[j].working_width),
                 kOnlyOnThreeD + ": a 2-D line has no lateral "
                 "contact point to keep on the strip; remove it here");
      };
      const std::string pf = "pantographs[" + std::to_string(i) + "]";
      check(p.collectors, pf + ".collectors");
      for (std::size_t h = 0; h < p.heads.size(); ++h) check(p.heads[h].collectors, pf + ".heads[" + std::to_string(h) + "].collectors");
    }
}

// Unique names, and a net uplift that pushes each pantograph up.
void validate_pantographs(const Scene& s) {
  std::set<std::string> names;
  for (std::size_t i = 0; i < s.pantographs.size(); ++i) {
    const auto& p = s.pantographs[i];
    const std::string pre = "pantographs[" + std::to_string(i) + "].";
    if (!names.insert(p.name).second) fail(pre + "name", "'" + p.name + "'", "unique among pantographs");
    // The uplift F0 + a v^2 pushes the head up against the wire; a net downward push is not a
    // pantograph (it would pull the head off the wire and the roof spring alone cannot hold it).
    const double v = s.train_speed, uplift = p.net_uplift(v);
    if (!p.moving_force && uplift < 0.0) {
      // Name the term that pulls down most (the frame's, or a head's, for the knee in use).
      std::string f = pre + (p.knee_trailing && p.aero_coefficient_trailing ? "aero_coefficient_trailing" : "aero_coefficient");
      double worst = p.frame_aero();
      for (std::size_t h = 0; h < p.heads.size(); ++h) {
        const double a = PantographSpec::head_aero(p.heads[h], p.knee_trailing);
        if (a < worst) {
          worst = a;
          f = pre + "heads[" + std::to_string(h) + "]." +
              (p.knee_trailing && p.heads[h].aero_coefficient_trailing ? "aero_coefficient_trailing" : "aero_coefficient");
        }
      }
      fail(f, fmt(worst),
           "a net uplift >= 0 at " + fmt(v * 3.6) + " km/h (knee " + (p.knee_trailing ? "trailing" : "leading") +
               "): static_uplift + (frame and heads' aero coefficients) v^2 = " + fmt(uplift) +
               " N; a net downward aerodynamic pull is not physical for a pantograph in service");
    }
  }
}

void validate_imperfections(const Scene& s, double line) {
  if ((s.imperfections.stagger_std > 0.0 || !s.imperfections.stagger_errors.empty()) && !s.stagger)
    fail(s.imperfections.stagger_std > 0.0 ? "imperfections.stagger_std" : "imperfections.stagger_errors", "(given)",
         "a 3-D line: give the design stagger (scene field 'stagger') the errors move");
  if (s.imperfections.any()) {
    if (s.endless)
      fail("imperfections", "(given)", "a finite line: an endless line repeats one perfect span");
    // The mesh carries a wavelength of at least two elements (shorter ones alias onto longer ones).
    const IrregularitySpec& ir = s.imperfections.contact_wire_irregularity;
    if (ir.rms > 0.0 && ir.wavelength_min < 2.0 * s.numerics.element_length)
      fail("imperfections.contact_wire_irregularity.wavelength_min", fmt(ir.wavelength_min),
           "at least two elements (2 x numerics.element_length = " + fmt(2.0 * s.numerics.element_length) +
               " m): the mesh cannot carry a shorter wave");
    for (std::size_t i = 0; i < s.imperfections.point_masses.size(); ++i)
      if (s.imperfections.point_masses[i].station > line + 1e-9)
        fail("imperfections.point_masses[" + std::to_string(i) + "].station", fmt(s.imperfections.point_masses[i].station),
             "on the line, [0, " + fmt(line) + "] m");
  }
}

void validate_lateral(const Scene& s, double line) {
  if (!s.lateral()) return;
  // A strip's own working width lies within the head's horns (pantograph_head.horn_width).
  auto check_strips = [&](const std::vector<CollectorSpec>& cs, const std::string& field) {
    for (std::size_t j = 0; j < cs.size(); ++j)
      if (cs[j].working_width && *cs[j].working_width > s.pantograph_head.horn_width + 1e-12)
        fail(field + "[" + std::to_string(j) + "].working_width", fmt(*cs[j].working_width),
             "at most pantograph_head.horn_width = " + fmt(s.pantograph_head.horn_width) + " m");
  };
  for (std::size_t i = 0; i < s.pantographs.size(); ++i) {
    const std::string pf = "pantographs[" + std::to_string(i) + "]";
    check_strips(s.pantographs[i].collectors, pf + ".collectors");
    for (std::size_t h = 0; h < s.pantographs[i].heads.size(); ++h)
      check_strips(s.pantographs[i].heads[h].collectors, pf + ".heads[" + std::to_string(h) + "].collectors");
  }
  // A 3-D line's lateral substeps load each leaning dropper with its elastic tension at q_n and the
  // lean's change (lateral_step.cpp), which a dropper at the step's middle does not carry.
  if (s.lateral() && s.numerics.droppers == SpringStep::kImplicit)
    fail("numerics.droppers", "'implicit' (on a 3-D line)",
         "explicit on a 3-D line (its lateral plane loads the leaning droppers with their tension at q_n)");
  // An endless line repeats its block of spans: a stagger pattern repeats with it (the block
  // moves by whole patterns), and so does one radius for the whole line; a curve placed by
  // station or a list per support does not.
  if (s.endless && !s.alignment.curves.empty())
    fail("alignment.curves", "(given with line.endless: true)",
         "a finite line: curves are placed by station; an endless line takes alignment.radius (every span on one curve)");
  if (s.endless && s.stagger && s.stagger->per_support)
    fail("stagger.per_support", "true (with line.endless: true)",
         "false on an endless line: give the stagger as a pattern repeated over the supports");
  if (s.endless && s.stagger) {
    const std::size_t a = s.stagger->contact_wire.size(), b = std::max<std::size_t>(1, s.stagger->messenger.size());
    if (a * b / std::gcd(a, b) > 8)
      fail("stagger.contact_wire", "(a pattern of " + std::to_string(a) + " with a messenger pattern of " + std::to_string(b) + ")",
           "on an endless line, patterns that repeat together within 8 supports (the block moves by whole patterns)");
  }
  const double half = 0.5 * s.pantograph_head.working_width;
  if (s.stagger) {
    for (std::size_t i = 0; i < s.stagger->contact_wire.size(); ++i)
      if (std::fabs(s.stagger->contact_wire[i]) >= half)
        fail("stagger.contact_wire[" + std::to_string(i) + "]", fmt(s.stagger->contact_wire[i]),
             "inside the pantograph head's working width, |stagger| < " + fmt(half) + " m (pantograph_head.working_width / 2)");
    if (s.stagger->per_support) {
      // Supports along the line, counting an overlap's shared supports once.
      const std::size_t line_supports = s.spans.size() + 1;
      if (s.stagger->contact_wire.size() != line_supports)
        fail("stagger.contact_wire", "(" + std::to_string(s.stagger->contact_wire.size()) + " values)",
             "one per support of the line with per_support: true (" + std::to_string(line_supports) + ")");
      if (!s.stagger->messenger.empty() && s.stagger->messenger.size() != line_supports)
        fail("stagger.messenger", "(" + std::to_string(s.stagger->messenger.size()) + " values)",
             "one per support of the line with per_support: true (" + std::to_string(line_supports) + ")");
    }
  }
  for (std::size_t i = 0; i < s.alignment.curves.size(); ++i)
    if (s.alignment.curves[i].start >= line)
      fail("alignment.curves[" + std::to_string(i) + "].start", fmt(s.alignment.curves[i].start), "on the line, below " + fmt(line) + " m");
}

void validate_endless(const Scene& s) {
  if (!s.numerics.windowed())
    fail("numerics.window", "off", "auto or {ahead, behind} on an endless line (only the window around the train is modelled)");
  if (!s.train_end) fail("train.end", "(missing)", "required on an endless line: the train front's station where the pass ends, m");
  if (s.droppers && s.droppers->per_span)
    fail("droppers.positions_per_span", "(given)", "an endless line repeats one span: give droppers.positions");
  if (s.output.analysis_first_span && s.output.analysis_last_span &&
      !(0 <= *s.output.analysis_first_span && *s.output.analysis_first_span < *s.output.analysis_last_span))
    fail("output.analysis_spans", "[" + std::to_string(*s.output.analysis_first_span) + ", " + std::to_string(*s.output.analysis_last_span) + "]",
         "0 <= first < last (span indices along the endless line)");
  if (s.train_start && *s.train_end < *s.train_start)
    fail("train.end", fmt(*s.train_end), ">= train.start (" + fmt(*s.train_start) + ")");
  if (s.numerics.element_length > s.spans.front() + 1e-12)
    fail("numerics.element_length", fmt(s.numerics.element_length), "at most the span length");
}

void validate_finite_line(const Scene& s, double line) {
  const int a0 = s.analysis_first(), a1 = s.analysis_last();
  if (a0 < 0 || a1 > static_cast<int>(s.spans.size()) || a0 >= a1)
    fail("output.analysis_spans", "[" + std::to_string(a0) + ", " + std::to_string(a1) + "]",
         "0 <= first < last <= span count (" + std::to_string(s.spans.size()) + ")");
  if (s.numerics.element_length > *std::min_element(s.spans.begin(), s.spans.end()) + 1e-12)
    fail("numerics.element_length", fmt(s.numerics.element_length), "at most the shortest span");
  if (s.train_start && s.train_end && *s.train_end < *s.train_start)
    fail("train.end", fmt(*s.train_end), ">= train.start (" + fmt(*s.train_start) + ")");
  if (s.train_end && *s.train_end > line + 1e-9)
    fail("train.end", fmt(*s.train_end), "at most the line length " + fmt(line) + " m");
}

}  // namespace

// What a rigid conductor rail does not model yet is refused rather than run wrongly.
void validate_rigid(const Scene& s) {
  if (std::none_of(s.sections.begin(), s.sections.end(), [](const SectionSpec& sec) { return sec.rigid; })) return;
  if (s.endless)
    fail("line.endless", "true (with conductor_rail)", "false: the endless block is laid by the tensioned wire's wave speed");
  if (s.numerics.windowed() && !s.numerics.window_auto)
    fail("numerics.window", "(lengths given with conductor_rail)",
         "auto, or off: a tension-free profile's bending waves run the whole section, so the window holds whole "
         "sections (those within a span of a pantograph), not lengths of its own");
  // Wear thins the contact wire alone; the model's beam is profile and wire together, whose
  // mass and EI a worn wire changes by another law (not modelled).
  if (s.imperfections.contact_wire_wear.any())
    fail("imperfections.contact_wire_wear", "(given with conductor_rail)",
         "none: the wear law scales the whole beam, a rail's beam is mostly the aluminium profile");
  // A beam, not a chain: under its weight the profile must sag less than a fiftieth of its span
  // (simply supported, 5 q L^4 / (384 EI): the small deflections its beam theory needs; the shipped
  // profile sags a thousandth). A softer one hangs as no rail does and the static state runs away.
  // The same across the track under the mean wind's drag on the profile (the lateral plane's small
  // deflections; a profile of EI 1 N m^2 would blow out kilometres and go NaN).
  const double wind_q = s.wind && s.lateral()
                            ? 0.5 * s.wind->air_density * s.wind->conductor_rail.drag_coefficient *
                                  s.wind->conductor_rail.diameter * s.wind->speed * s.wind->speed
                            : 0.0;
  // The least EI a span of the profile needs under q per metre: 5 q L^4 / (384 EI) <= L / 50.
  auto least_ei = [](double q, double span) { return 250.0 * q * span * span * span / 384.0; };
  auto stiff_enough = [&](const std::string& field, double ei, double span, double q, const char* under,
                          const char* way, const std::string& note = "") {
    const double least = least_ei(q, span);
    if (!(ei >= least))
      fail(field, fmt(ei) + note,
           "at least " + fmt_limit(least, true, 10) + " N m^2 here: the profile would " + way + " " + fmt(5.0 * q * std::pow(span, 4) / (384.0 * ei)) +
               " m under " + under + " over a " + fmt(span) + " m span (5 q L^4 / (384 EI)), more than a fiftieth of it");
  };
  for (std::size_t i = 0; i < s.sections.size(); ++i) {
    const SectionSpec& sec = s.sections[i];
    if (!sec.rigid) continue;
    const std::string f = s.section_field(i, "conductor_rail");
    const double longest = *std::max_element(sec.spans.begin(), sec.spans.end());
    // A span no profile of the allowed EI could take under its weight is the span's to shorten.
    const double q_weight = sec.contact_wire.linear_mass * s.gravity, least = least_ei(q_weight, longest);
    if (least > kMaxRailBendingStiffness)
      fail(spans_field(s, i), fmt(longest) + " m",
           "a rigid rail's span short enough for a profile of at most " + fmt(kMaxRailBendingStiffness) +
               " N m^2 (this one needs " + fmt(least) +
               " N m^2 so as to sag less than a fiftieth of it under its weight); supports every 8-12 m in service");
    stiff_enough(f + ".bending_stiffness", sec.contact_wire.bending_stiffness, longest, q_weight, "its weight", "sag");
    if (wind_q > 0.0)
      stiff_enough(f + ".lateral_bending_stiffness", sec.rail_lateral_bending_stiffness.value_or(sec.contact_wire.bending_stiffness),
                   longest, wind_q, "the mean wind (wind.speed)", "blow out",
                   sec.rail_lateral_bending_stiffness ? "" : " (absent: the bending_stiffness)");
    if (sec.rail_transition_piece) {
      // The softened end span, its EI rising over the piece: the same fiftieth, from its sag.
      const SectionSpec::TransitionPiece& piece = *sec.rail_transition_piece;
      const double ei = sec.contact_wire.bending_stiffness, end_ei = piece.end_bending_stiffness;
      for (const bool at_start : {true, false}) {
        if (!(at_start ? transition_piece_at_start(s, i) : transition_piece_at_end(s, i))) continue;
        const double span = at_start ? sec.spans.front() : sec.spans.back();
        const double length = std::min(piece.length, span);  // (a longer piece is refused below)
        auto sag = [&](double e) { return softened_span_sag(q_weight, span, ei, e, length); };
        if (sag(end_ei) <= span / 50.0) continue;
        double low = 0.0, high = ei;  // (the whole span at ei sags less: checked above)
        for (int k = 0; k < 60; ++k) (sag(0.5 * (low + high)) <= span / 50.0 ? high : low) = 0.5 * (low + high);
        fail(f + ".transition_piece.end_bending_stiffness", fmt(end_ei),
             "at least " + fmt_limit(high, true, 10) + " N m^2 with this piece's length " + fmt(length) + " m: the profile would sag " +
                 fmt(sag(end_ei)) + " m under its weight over its " + fmt(span) + " m end span (simply supported, its EI "
                 "rising over the piece), more than a fiftieth of it");
      }
    }
  }
  for (std::size_t i = 0; i < s.sections.size(); ++i) {
    const SectionSpec& sec = s.sections[i];
    if (!sec.rail_transition_piece) continue;
    const std::string f = s.section_field(i, "conductor_rail.transition_piece");
    const SectionSpec::TransitionPiece& piece = *sec.rail_transition_piece;
    if (piece.end_bending_stiffness > sec.contact_wire.bending_stiffness)
      fail(f + ".end_bending_stiffness", fmt(piece.end_bending_stiffness),
           "at most the profile's bending_stiffness (" + fmt(sec.contact_wire.bending_stiffness) +
               " N m^2): the piece is the profile made softer toward its end");
    const bool first = transition_piece_at_start(s, i), last = transition_piece_at_end(s, i);
    if (!first && !last)
      fail(f, "(given)",
           "a rail section joined to a catenary section, the piece lying at that joint: no catenary section "
           "joins this one; remove it here");
    const double room = std::min(first ? sec.spans.front() : 1e300, last ? sec.spans.back() : 1e300);
    if (piece.length > room + 1e-9)
      fail(f + ".length", fmt(piece.length), "(0, " + fmt(room) + "] m: within the end span it lies in");
  }
  if (s.sections.size() > 1 && !(s.overlap && s.overlap->support_rise))
    fail("overlap.support_rise", "(missing with conductor_rail)",
         "the end ramp's rise in m, [0, 2]: eq. 6-8 derive it from a tensioned wire's sag, a rigid profile has none");
}

// The longest a short clamped wire (a stitch wire, a bridle) centred on each support that
// carries one (`carries(k)`, support k of the section's spans) may be, each clamp within its span:
// where both of a span's supports carry one, the halves must not meet (below the span); where one
// does, its half lies within it (below twice the span). *limiting: the span that sets it.
template <class Carries>
double least_clamp_room(const std::vector<double>& spans, Carries&& carries, std::size_t* limiting) {
  double allowed = 1e300;
  for (std::size_t j = 0; j < spans.size(); ++j) {
    const int clamps = carries(j) + carries(j + 1);
    const double room = clamps == 2 ? spans[j] : 2.0 * spans[j];
    if (clamps > 0 && room < allowed) {
      allowed = room;
      *limiting = j;
    }
  }
  return allowed;
}

// Stitch wires: hung from a messenger around intermediate supports, each within its spans.
void validate_stitched(const Scene& s) {
  const bool any = std::any_of(s.sections.begin(), s.sections.end(), [](const SectionSpec& sec) { return sec.stitch_wire.has_value(); });
  if (!any) return;
  for (std::size_t si = 0; si < s.sections.size(); ++si) {
    const SectionSpec& sec = s.sections[si];
    if (!sec.stitch_wire) continue;
    const std::string f = s.section_field(si, "stitch_wire");
    if (!sec.messenger || !sec.droppers)
      fail(f, "(given)", "a stitch wire hangs from a messenger and carries droppers: add messenger and droppers or remove it");
    if (sec.spans.size() < 2 && !s.endless)  // (an endless line's one span repeats: supports on both sides)
      fail(f, "(given on a section of 1 span)", "a section with intermediate supports (2 spans or more): a stitch wire hangs around one");
    const StitchWireSpec& st = *sec.stitch_wire;
    const std::size_t n = sec.spans.size();
    if (!st.at_supports.empty()) {
      if (s.endless)
        fail(f + ".at_supports", "(given on the endless line)", "absent: the endless line's one span repeats, every support carries one");
      if (st.at_supports.back() > static_cast<int>(n) - 1)
        fail(f + ".at_supports", std::to_string(st.at_supports.back()),
             "an intermediate support of the section, 1 to " + std::to_string(n - 1) + " (its " + std::to_string(n) + " spans)");
    }
    // The supports that carry one: an endless line's one span repeats, both its supports carrying
    // one; a section's end supports carry none.
    auto carries = [&](std::size_t k) { return s.endless || (k > 0 && k < n && st.at(static_cast<int>(k))); };
    if (!st.lengths.empty()) {
      if (s.endless)
        fail(f + ".lengths", "(given on the endless line)", "absent: the endless line's one span repeats, give length");
      const std::size_t carrying = st.at_supports.empty() ? n - 1 : st.at_supports.size();
      if (st.lengths.size() != carrying)
        fail(f + ".lengths", std::to_string(st.lengths.size()) + " lengths",
             std::to_string(carrying) + ", one per support that carries a stitch wire (" +
                 (st.at_supports.empty() ? "supports 1 to " + std::to_string(n - 1) : "at_supports") + ")");
    }
    // Each span holds the clamps of the stitch wires at its supports that carry one, half a length
    // from the support: where both do, the halves must not meet, where one does, it lies within the
    // span (a length below twice the span), so that a stitched line may end on short spans (toward
    // a portal, a joint with a rail). The section's end supports carry none; an endless line's one
    // span repeats, both its supports carrying one.
    auto half = [&](std::size_t k) { return carries(k) ? 0.5 * st.length_at(static_cast<int>(k)) : 0.0; };
    for (std::size_t i = 0; i < n; ++i) {
      const double a = half(i), b = half(i + 1);
      if (a + b < sec.spans[i]) continue;
      if (!st.lengths.empty()) {
        const int support = static_cast<int>(b > 0.0 ? i + 1 : i);
        fail(f + ".lengths[" + std::to_string(st.length_index(support)) + "]", fmt(st.length_at(support)),
             "a length whose clamps stay within span " + std::to_string(i) + " (" + fmt(sec.spans[i]) + " m): " +
                 (a > 0.0 && b > 0.0 ? "half the stitch wires' lengths at supports " + std::to_string(i) + " and " +
                                           std::to_string(i + 1) + " together (" + fmt(a) + " + " + fmt(b) + " m) below the span"
                                     : "half its length below the span"));
      }
      // One length for all: the range every span allows, and the span that sets it.
      std::size_t limiting = 0;
      const double allowed = least_clamp_room(sec.spans, carries, &limiting);
      const bool both = carries(limiting) && carries(limiting + 1);
      fail(f + ".length", fmt(st.length),
           "(0, " + fmt(allowed) + ") m: each clamp within its span, " + fmt(0.5 * st.length) + " m from its support (span " +
               std::to_string(limiting) + ", " + fmt(sec.spans[limiting]) + " m, holds " +
               (both ? "the clamps of the stitch wires at both its supports" : "one clamp") + ")");
    }
  }
}

// A compound catenary: messenger, droppers to the auxiliary messenger, hangers to one contact wire.
void validate_compound(const Scene& s) {
  for (std::size_t si = 0; si < s.sections.size(); ++si) {
    const SectionSpec& sec = s.sections[si];
    if (!sec.auxiliary_messenger && !sec.hangers) continue;
    const auto in_section = [&](const std::string& name) { return s.section_field(si, name); };
    if (!sec.auxiliary_messenger)
      fail(in_section("hangers"), "(given)", "hangers hang the contact wire from an auxiliary messenger: add auxiliary_messenger or remove hangers");
    const std::string f = in_section("auxiliary_messenger");
    if (!sec.hangers)
      fail(f, "(given without hangers)", "hangers from it to the contact wire (positions, axial_stiffness, ...)");
    if (!sec.messenger || !sec.droppers)
      fail(f, "(given)", "the droppers hang it from a messenger: add messenger and droppers");
    if (!(sec.auxiliary_messenger->tension > 0.0)) fail(f + ".tension", fmt(sec.auxiliary_messenger->tension), "> 0 N");
    if (!(sec.auxiliary_messenger->height < s.encumbrance))
      fail(f + ".height", fmt(sec.auxiliary_messenger->height),
           "(0, " + fmt(s.encumbrance) + ") m: below the messenger (line.encumbrance above the contact wire at the supports)");
    if (sec.contact_wire_count != 1)
      fail(in_section("contact_wire_count"), std::to_string(sec.contact_wire_count), "1 on a compound catenary (its hangers hold one contact wire)");
    if (sec.stitch_wire) fail(in_section("stitch_wire"), "(given with auxiliary_messenger)", "none: a line is stitched or compound, not both");
  }
}

// Bridles: a trolley wire's (no messenger, one contact wire), each hung from its support, the
// clamps at its ends within the spans beside it.
void validate_bridles(const Scene& s) {
  for (std::size_t si = 0; si < s.sections.size(); ++si) {
    const SectionSpec& sec = s.sections[si];
    if (!sec.bridle) continue;
    const auto in_section = [&](const std::string& name) { return s.section_field(si, name); };
    const std::string f = in_section("bridle");
    if (sec.messenger)
      fail(f, "(given with messenger)",
           "a trolley wire's: a bridle hangs the contact wire from its supports; on a catenary the messenger carries it "
           "(stitch_wire evens its supports)");
    if (sec.contact_wire_count != 1)
      fail(in_section("contact_wire_count"), std::to_string(sec.contact_wire_count), "1 with a bridle (its clamps hold one contact wire)");
    if (sec.steady_arms && sec.steady_arms->hinged_arm)
      fail(in_section("steady_arms"), "(a hinged arm, with a bridle)",
           "a spring (stiffness, mass) or none: the support holds the bridle's middle, which a registration arm does not");
    // The contact wire is free at its supports, which hardly reflect its waves: they run the
    // section's length and back, and a window that holds only what is near the pantograph misses
    // them (measured in docs/trolley_wire.md, "What is not modelled").
    if (s.endless)
      fail(f, "(given on the endless line)",
           "a finite line: the endless line needs the moving window, which a bridled wire's far-running waves defeat");
    if (s.numerics.windowed() && !s.numerics.window_auto)
      fail("numerics.window", "(lengths given with a bridle)",
           "auto, or off: under bridles the contact wire's waves run the whole section, so the window holds whole "
           "sections (those within a span of a pantograph), not lengths of its own");
    const std::size_t n = sec.spans.size();
    if (n < 2)
      fail(f, "(given on a section of 1 span)", "a section with intermediate supports (2 spans or more): a bridle hangs at one");
    // Half a length either side of each intermediate support (the section's ends carry none).
    std::size_t limiting = 0;
    const double allowed = least_clamp_room(sec.spans, [&](std::size_t k) { return k > 0 && k < n; }, &limiting);
    if (!(sec.bridle->length < allowed))
      fail(f + ".length", fmt(sec.bridle->length),
           "(0, " + fmt(allowed) + ") m: its clamps within span " + std::to_string(limiting) + " (" + fmt(sec.spans[limiting]) +
               " m, " + (limiting > 0 && limiting + 1 < n ? "the clamps of the bridles at both its supports" : "one clamp") + ")");
  }
}

// A messenger carries the line through its droppers: without any it would hang apart, loading
// nothing (what hangs from it on a stitched or compound line is checked with those kinds).
void validate_messengers(const Scene& s) {
  for (std::size_t si = 0; si < s.sections.size(); ++si) {
    const SectionSpec& sec = s.sections[si];
    if (sec.messenger && !sec.droppers)
      fail(s.section_field(si, "messenger"), "(given without droppers)",
           "droppers that hang the contact wire from it; a trolley wire has no messenger: remove it");
  }
}

void validate(const Scene& s) {
  const double line = s.line_length();
  validate_sections(s);
  validate_rigid(s);
  validate_stitched(s);
  validate_compound(s);
  validate_bridles(s);
  validate_messengers(s);
  validate_limits(s);
  validate_acting_fields(s);
  validate_pantographs(s);
  validate_imperfections(s, line);
  validate_lateral(s, line);
  if (s.endless) {
    validate_endless(s);
    return;
  }
  validate_finite_line(s, line);
}

}  // namespace catenary_sim
