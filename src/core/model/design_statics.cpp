#include "model/design_statics.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "catenary_sim/core/model/lateral.hpp"
#include "catenary_sim/core/model/statics.hpp"
#include "catenary_sim/core/model/wire_band.hpp"
#include "model/spd_solver.hpp"
#include "util/format.hpp"

namespace catenary_sim {

namespace {

bool holds(const Wire& w, int dof) { return dof >= w.w_dof && dof < w.w_dof + w.nodes(); }

const Wire& wire_of(const Model& m, int dof) { return m.wires[wire_holding(m, dof)]; }

}  // namespace

double hang_bridle(const Scene& scene, const Model& m, Wire& w, std::vector<double>& reaction) {
  const double H = scene.contact_wire_height;
  const int n = w.nodes();
  std::vector<double> load(n);
  for (int i = 0; i < n; ++i) load[i] = -scene.gravity * m.mass[w.w_dof + i];
  for (const WireClamp& c : m.clamps)
    if (holds(w, c.upper_dof)) load[c.upper_dof - w.w_dof] -= c.static_force;
  solve_wire_statics(w, load, {w.support_nodes.front()}, {H}, w.height, w.slope, reaction);
  // (A rigid rise: the band has no force from it, the reaction stays.)
  const double rise = H - std::min(w.height.front(), w.height.back());
  for (double& y : w.height) y += rise;
  return std::max(bridle_arm_rise(w, 0), bridle_arm_rise(w, n - 1));
}

namespace {

// A trolley wire's bridles (BridleSpec) once the contact wire is solved held at its anchors and at
// the clamps at the working height (each clamp's static force set to the contact wire's reaction
// there): the clamp pulls the bridle's end down. The bridle, held at its middle only, hangs from
// there in a V under those forces and its weight; it is raised until its lower end is at the
// working height, the other end above by what its arms' loads differ (the clamp then a short
// link). Its reaction at the middle is the support's preload (design_statics).
void bridle_statics(const Scene& scene, const Section& info, Model& m, std::vector<std::vector<double>>& react) {
  const Wire* steepest = nullptr;  // refused by the worst, as the plan's check is (lateral.cpp)
  double worst = 0.0;
  for (int wi : info.clamped_wires) {
    const double slope = hang_bridle(scene, m, m.wires[wi], react[wi]);
    if (!(slope <= worst) && !std::isnan(worst)) {  // (a NaN slope is the worst)
      worst = slope;
      steepest = &m.wires[wi];
    }
  }
  if (!steepest || worst <= kSteepestBridleArm) return;
  // The tension that would do: the string's share of a slope falls as 1 / tension, the bridle's
  // bending's does not, so the steepest is hung again and its slope taken as a / T + b through the
  // last two tensions (a secant in 1 / T) until it meets the limit. Far below it a V's slope is not
  // that line (the arms are no longer small angles): the string's estimate from the last slope
  // then raises the tension until the fit holds.
  double t = steepest->spec.tension, s = worst, needed = t * worst / kSteepestBridleArm;
  Wire again = *steepest;
  for (int tries = 0; tries < 30; ++tries) {
    again.spec.tension = needed;
    assemble_band(again, {});
    std::vector<double> reaction;
    const double s2 = hang_bridle(scene, m, again, reaction);
    if (!std::isfinite(s2)) break;
    if (std::fabs(s2 - kSteepestBridleArm) < 1e-4 * kSteepestBridleArm) break;  // (T to about 0.01 %)
    const double a = (s - s2) / (1.0 / t - 1.0 / needed), b = s - a / t;
    t = needed;
    s = s2;
    needed = a > 0.0 && b < kSteepestBridleArm ? a / (kSteepestBridleArm - b) : t * s / kSteepestBridleArm;
  }
  refuse_slack_bridle(scene, *steepest, worst,
                      "in its V, its middle " +
                          fmt(steepest->height[steepest->support_nodes.front()] - scene.contact_wire_height) + " m above the wire",
                      scene.lateral() ? "; on a 3-D line the arms' turn in plan is checked once the V holds, and may need more" : "",
                      std::isfinite(needed) ? std::optional<double>(needed) : std::nullopt);
}

}  // namespace

double bridle_arm_rise(const Wire& w, int end) {
  const int mid = w.support_nodes.front();
  return std::fabs(w.height[mid] - w.height[end]) / std::fabs(w.x[end] - w.x[mid]);
}

void refuse_slack_bridle(const Scene& scene, const Wire& w, double slope, const std::string& how, const std::string& advice,
                         std::optional<double> needed) {
  const std::string field = scene.section_field(w.section, "bridle");
  const double tension = scene.sections[w.section].bridle->tension;
  throw SceneError("scene field '" + field + ".tension' = " + fmt(tension) + " N: to carry the contact wire, the bridle at station " +
                   fmt(w.x[w.support_nodes.front()]) + " m would run its arms at a slope of " + fmt(slope) + " (" + how +
                   "); at most " + fmt(kSteepestBridleArm) + ", the model's small angles: raise " + field + ".tension (about " +
                   (needed ? fmt(*needed) + " N, from the bridles' statics hung again" :
                             fmt(tension * slope / kSteepestBridleArm) + " N; the slopes fall nearly as 1 / tension") +
                   ", at most 1e5)" + advice);
}

namespace {

// One section's statics: the contact wire(s) held at the supports and droppers, then the messenger
// under the dropper tensions, a few fixed-point passes for the droppers' weight.
void section_statics(const Scene& scene, std::size_t si, const std::vector<std::vector<double>>& section_supports,
                     Model& m, std::vector<double>& weight_len, std::vector<double>& dropper_len,
                     std::vector<std::vector<double>>& react) {
  const double g = scene.gravity;
  const double H = scene.contact_wire_height;
  const SectionSpec& sec = scene.sections[si];
  const Section& info = m.sections[si];
  // Kg/m of a dropper's (or a compound line's hanger's) own wire.
  auto mu_of = [&](std::size_t k) { return m.droppers[k].hanger ? sec.hangers->linear_mass : sec.droppers->linear_mass; };
  const int nspan = static_cast<int>(sec.spans.size());
  auto transition = [&](int span) {
    return (span == 0 && sec.first_span_transition) || (span == nspan - 1 && sec.last_span_transition);
  };
  std::vector<std::size_t> mine;
  for (std::size_t k = 0; k < m.droppers.size(); ++k)
    if (m.droppers[k].section == static_cast<int>(si)) mine.push_back(k);
  // (A stitch wire's clamps take the messenger's heights of the pass before: two more passes.)
  // (as do a compound line's auxiliary messenger's dropper heights)
  const int passes = mine.empty() ? 1 : info.clamped_wires.empty() && info.auxiliary < 0 ? 4 : 6;
  std::vector<SpdSolver> solver(m.wires.size());  // per wire: its pattern is the same every pass
  for (int pass = 0; pass < passes; ++pass) {
    for (int wi : info.wires) {
      if (wi == info.messenger) continue;
      Wire& w = m.wires[wi];
      const int n = w.nodes();
      std::vector<double> load(n);
      for (int i = 0; i < n; ++i) load[i] = -g * m.mass[w.w_dof + i];
      std::vector<int> pn;
      std::vector<double> ph;
      const int ns = static_cast<int>(w.support_nodes.size());
      for (int k = 0; k < ns; ++k) {
        if (sec.bridle && k > 0 && k < ns - 1) continue;  // hung from the bridle's clamps (below)
        pn.push_back(w.support_nodes[k]);
        ph.push_back(H + (k == 0 ? info.rise_first : 0.0) + (k == ns - 1 ? info.rise_last : 0.0));
      }
      std::vector<WireClamp*> clamps;  // a bridle's, held from node first_clamp of pn on, in this order
      const std::size_t first_clamp = pn.size();
      if (sec.bridle)
        for (WireClamp& c : m.clamps)
          if (holds(w, c.lower_dof)) {
            clamps.push_back(&c);
            pn.push_back(c.lower_dof - w.w_dof);
            ph.push_back(H);
          }
      for (std::size_t k : mine) {
        const Dropper& d = m.droppers[k];
        if (d.contact_dof < w.w_dof || d.contact_dof >= w.w_dof + n) continue;
        const int node = d.contact_dof - w.w_dof;
        load[node] -= 0.5 * g * mu_of(k) * weight_len[k];
        const double s = (d.x - section_supports[si][d.span]) / sec.spans[d.span];
        pn.push_back(node);
        ph.push_back(transition(d.span) ? H : H - sec.contact_wire.presag * 4.0 * s * (1.0 - s));
      }
      solve_wire_statics(w, load, pn, ph, w.height, w.slope, react[wi], &solver[wi]);
      if (sec.bridle) {
        for (std::size_t j = 0; j < clamps.size(); ++j) clamps[j]->static_force = react[wi][first_clamp + j];
        bridle_statics(scene, info, m, react);
        continue;  // (no droppers)
      }
      // Dropper tensions: the reactions at the dropper nodes, in the order they were added.
      std::size_t r = static_cast<std::size_t>(ns);
      for (std::size_t k : mine)
        if (m.droppers[k].contact_dof >= w.w_dof && m.droppers[k].contact_dof < w.w_dof + n)
          m.droppers[k].static_tension = react[wi][r++];
    }
    if (info.messenger < 0) break;
    Wire& mwm = m.wires[info.messenger];
    // A compound line's auxiliary messenger: under its weight and its hangers' tensions, held at
    // its anchors and, at each dropper, `height` above the contact wire's design shape (its
    // reactions there are the dropper tensions).
    if (info.auxiliary >= 0) {
      Wire& aux = m.wires[info.auxiliary];
      const Wire& cw = m.wires[info.wires.front()];  // the one contact wire (validate_compound)
      const double h = sec.auxiliary_messenger->height;
      const int n = aux.nodes();
      std::vector<double> load(n);
      for (int i = 0; i < n; ++i) load[i] = -g * m.mass[aux.w_dof + i];
      std::vector<int> pn{aux.support_nodes.front(), aux.support_nodes.back()};
      for (std::size_t k : mine) {
        const Dropper& d = m.droppers[k];
        if (holds(aux, d.messenger_dof)) load[d.messenger_dof - aux.w_dof] -= d.static_tension + 0.5 * g * mu_of(k) * weight_len[k];
        if (holds(aux, d.contact_dof)) {
          load[d.contact_dof - aux.w_dof] -= 0.5 * g * mu_of(k) * weight_len[k];
          pn.push_back(d.contact_dof - aux.w_dof);
        }
      }
      std::vector<double> ph;
      for (int node : pn) ph.push_back(cw.height[node] + h);  // (the same stations as the contact wire's)
      solve_wire_statics(aux, load, pn, ph, aux.height, aux.slope, react[info.auxiliary], &solver[info.auxiliary]);
      std::size_t r = 2;
      for (std::size_t k : mine)
        if (holds(aux, m.droppers[k].contact_dof)) m.droppers[k].static_tension = react[info.auxiliary][r++];
    }
    // The stitch wires: each under its weight and its droppers' tensions, held at its clamps at
    // the messenger's heights there (the last pass's; level at the encumbrance on the first).
    for (int wi : info.clamped_wires) {
      Wire& w = m.wires[wi];
      const int n = w.nodes();
      std::vector<double> load(n);
      for (int i = 0; i < n; ++i) load[i] = -g * m.mass[w.w_dof + i];
      for (std::size_t k : mine)
        if (holds(w, m.droppers[k].messenger_dof))
          load[m.droppers[k].messenger_dof - w.w_dof] -= m.droppers[k].static_tension + 0.5 * g * mu_of(k) * weight_len[k];
      const std::vector<int> pn{0, n - 1};
      std::vector<double> ph(2, H + scene.encumbrance);
      for (const WireClamp& c : m.clamps)
        if (holds(w, c.lower_dof) && !mwm.height.empty()) ph[c.lower_dof == w.w_dof ? 0 : 1] = mwm.height[c.upper_dof - mwm.w_dof];
      solve_wire_statics(w, load, pn, ph, w.height, w.slope, react[wi], &solver[wi]);
      for (WireClamp& c : m.clamps)
        if (holds(w, c.lower_dof)) c.static_force = react[wi][c.lower_dof == w.w_dof ? 0 : 1];
    }
    const int n = mwm.nodes();
    std::vector<double> mload(n);
    for (int i = 0; i < n; ++i) mload[i] = -g * m.mass[mwm.w_dof + i];
    for (std::size_t k : mine) {
      const Dropper& d = m.droppers[k];
      if (holds(mwm, d.messenger_dof)) mload[d.messenger_dof - mwm.w_dof] -= d.static_tension + 0.5 * g * mu_of(k) * weight_len[k];
    }
    for (const WireClamp& c : m.clamps)
      if (holds(mwm, c.upper_dof)) mload[c.upper_dof - mwm.w_dof] -= c.static_force;
    std::vector<int> mpn(mwm.support_nodes.begin(), mwm.support_nodes.end());
    std::vector<double> mph(mpn.size(), H + scene.encumbrance);
    solve_wire_statics(mwm, mload, mpn, mph, mwm.height, mwm.slope, react[info.messenger], &solver[info.messenger]);
    for (std::size_t k : mine) {
      const Dropper& d = m.droppers[k];
      const Wire& cwire = wire_of(m, d.contact_dof);
      const Wire& top = wire_of(m, d.messenger_dof);
      dropper_len[k] = top.height[d.messenger_dof - top.w_dof] - cwire.height[d.contact_dof - cwire.w_dof];
    }
    if (pass + 1 < passes)
      for (std::size_t k : mine) weight_len[k] = dropper_len[k];
  }
}

// The droppers' design lengths, unstretched lengths, stiffness and masses; a dropper that would
// have to push is refused.
void set_dropper_lengths(const Scene& scene, const std::vector<double>& weight_len,
                         const std::vector<double>& dropper_len, Model& m) {
  for (std::size_t k = 0; k < m.droppers.size(); ++k) {
    Dropper& d = m.droppers[k];
    const SectionSpec& sec = scene.sections[d.section];
    d.length = dropper_len[k];
    const DropperSpec& spec = d.hanger ? *sec.hangers : *sec.droppers;
    const std::string part = d.hanger ? "hanger" : "dropper";
    if (d.length <= 0.01) {
      // Named by the field that most directly lifts the wire above: a stitch wire's own tension
      // (it sags as L^2 / T between its clamps), the auxiliary's tension (it sags between its
      // droppers under the hangers), else the system height.
      const Wire& top = wire_of(m, d.messenger_dof);
      const bool holds_auxiliary = wire_of(m, d.contact_dof).is_auxiliary_messenger;
      const std::string low = holds_auxiliary ? "auxiliary messenger" : "contact wire";
      const std::string top_name = top.is_clamped_wire ? "stitch wire" : top.is_auxiliary_messenger ? "auxiliary messenger" : "messenger";
      std::string field, value, advice;
      if (top.is_clamped_wire) {
        field = scene.section_field(d.section, "stitch_wire.tension");
        value = fmt(sec.stitch_wire->tension) + " N";
        advice = "raise it, or shorten " + scene.section_field(d.section, "stitch_wire.length") + " (its sag grows as its length squared over its tension)";
      } else if (d.hanger) {
        field = scene.section_field(d.section, "auxiliary_messenger.tension");
        value = fmt(sec.auxiliary_messenger->tension) + " N";
        advice = "raise it, or raise auxiliary_messenger.height (" + fmt(sec.auxiliary_messenger->height) + " m)";
      } else {
        field = "line.encumbrance";
        value = fmt(scene.encumbrance) + " m";
        advice = "raise it or the " + top_name + "'s tension" +
                 (holds_auxiliary ? ", or lower auxiliary_messenger.height (" + fmt(sec.auxiliary_messenger->height) + " m)" : "") +
                 // (a stitch wire pulls the messenger down at its clamps by its tension's share)
                 (sec.stitch_wire ? ", or lower stitch_wire.tension (" + fmt(sec.stitch_wire->tension) + " N)" : "");
      }
      // (At least 1 cm: a dropper's fittings; a shorter or negative one cannot be built.)
      const std::string where = d.length > 0.0 ? " only " + fmt(d.length) + " m above the " + low + ", a " + part + " shorter than 0.01 m"
                                               : " " + fmt(-d.length) + " m below the " + low + ", a " + part + " of negative length";
      throw SceneError("scene field '" + field + "' = " + value + ": at x = " + fmt(d.x) + " m the " + top_name + " hangs" + where +
                       " (at least 0.01 m: its fittings); " + advice + ", or reduce the presag");
    }
    const int nspan = static_cast<int>(sec.spans.size());
    const bool in_transition = (d.span == 0 && sec.first_span_transition) || (d.span == nspan - 1 && sec.last_span_transition);
    if (d.static_tension <= 0.0 && in_transition)
      throw SceneError(part + "s: at x = " + fmt(d.x) + " m, in a transition span, the " + part + " would have to push (static force " +
                       fmt(d.static_tension) + " N): the raised support (rise d = " +
                       fmt(std::max(m.sections[d.section].rise_first, m.sections[d.section].rise_last)) +
                       " m) pulls the wire up past it; lower overlap.support_rise (or overlap.design_force) or hang " + part +
                       "s.transition_positions nearer the section's own support");
    if (d.static_tension <= 0.0 && sec.auxiliary_messenger && !d.hanger)
      throw SceneError("droppers: at x = " + fmt(d.x) + " m the dropper would have to push the auxiliary messenger up (static force " +
                       fmt(d.static_tension) + " N): held auxiliary_messenger.height (" + fmt(sec.auxiliary_messenger->height) +
                       " m) above the contact wire there, it must bend down more than its hangers' loads bend it; hang the "
                       "contact wire from hangers nearer each dropper (hangers.positions), or reduce contact_wire.presag (" +
                       fmt(sec.contact_wire.presag) + " m)");
    if (d.static_tension <= 0.0 && wire_of(m, d.messenger_dof).is_clamped_wire)
      throw SceneError("droppers: at x = " + fmt(d.x) + " m the dropper would have to push (static force " +
                       fmt(d.static_tension) + " N): the stitch wire it hangs from sags too far at stitch_wire.tension " +
                       fmt(sec.stitch_wire->tension) + " N; raise it, or reduce contact_wire.presag (" +
                       fmt(sec.contact_wire.presag) + " m)");
    if (d.static_tension <= 0.0)
      throw SceneError(part + "s: at x = " + fmt(d.x) + " m the " + part + " would have to push (static force " +
                       fmt(d.static_tension) + " N): contact_wire.presag " + fmt(sec.contact_wire.presag) +
                       " m is not reachable with tension-only " + part + "s; reduce it");
    d.unstretched_length = d.length / (1.0 + d.static_tension / spec.axial_stiffness);
    d.stiffness = spec.axial_stiffness / d.unstretched_length;
    // Half the dropper's mass on each end (the length its weight had in the statics, so that the
    // design state is an exact equilibrium).
    m.mass[d.contact_dof] += 0.5 * spec.linear_mass * weight_len[k];
    m.mass[d.messenger_dof] += 0.5 * spec.linear_mass * weight_len[k];
  }
}

// A hinged steady arm's inclination and k_A at the assembly (HingedArmSpec). The arm is a bar of
// length a hinged at the registration tube; the wire pulls its end outward with F_h, less k_w per
// metre the end moves out (k_w: the wire's own lateral stiffness there). Its moments about the
// hinge, with the wire's load W at the end, the clamp's weight there and its own at mid-length:
//   F_h a sin(theta) = (W + m_c g + m_a g / 2) a cos(theta).
// The spring's reaction f0 carries W and the tip mass (m_a / 3 + m_c) g, so the bracket is
// f0 + m_a g / 6. In the end's height z = -a sin(theta) the end moves out by tan(theta) dz, and
// the potential -F_h a cos(theta) + k_w (a cos(theta) - a cos(theta0))^2 / 2 - (m_c + m_a / 2) g
// a sin(theta) has d2/dz2 = F_h / (a cos^3 theta0) + k_w tan^2 theta0 at the assembly: the weights
// drop out, and that is eq. 4's k_A. The end's speed is z' / cos(theta0) (it moves out as it
// rises), so the arm's inertia on the wire's node is its tip mass (m_a / 3 + m_c) / cos^2 theta0;
// the share tan^2 theta0 of it has no weight (design_statics adds it to the node's mass and to f0
// alike). On a 3-D line (`in_plan`) the lateral plane moves the arm's end and its reaction acts
// back on the arm (LateralRegistration, lateral.hpp), which is the k_w tan^2 theta0 share as the
// wires give it at each instant: k_A keeps only F_h / (a cos^3 theta0).
void set_hinged_arm(const HingedArmSpec& arm, double g, const RegistrationLateral& wire, const std::string& field,
                    bool in_plan, SupportSpring& sp) {
  const double pull_off = arm.pull_off ? *arm.pull_off : wire.pull_off;
  const double bracket = sp.static_force + arm.linear_mass * arm.length * g / 6.0;
  const double theta = std::atan2(bracket, pull_off);
  // Steeper, k_A grows as 1 / cos^3 toward a rod hanging straight down, rigid to the line and
  // beyond any step; arms as built hang a few degrees.
  constexpr double kMaxInclination = 0.25 * M_PI;
  if (std::abs(theta) > kMaxInclination) {
    const std::string need = fmt_limit(std::abs(bracket) / std::tan(kMaxInclination), true);
    const std::string hangs = " m would hang " + fmt(theta * 180.0 / M_PI) + " degrees from its hinge under the " +
                              fmt(bracket) + " N the wire and its weight put on it";
    if (arm.pull_off)
      throw SceneError("scene field '" + field + ".pull_off' = " + fmt_given(pull_off) + " N: the arm at station " + fmt(sp.x) +
                       hangs + "; allowed: a pull-off of at least " + need + " N (within 45 degrees of horizontal)");
    throw SceneError("scene field 'stagger.contact_wire': the pull-off " + fmt(pull_off) + " N it gives the hinged arm at station " +
                     fmt(sp.x) + hangs + "; allowed: stagger and curves that pull each arm with at least " + need +
                     " N (within 45 degrees of horizontal), or steady_arms as a spring (stiffness, mass)");
  }
  const double c = std::cos(theta);
  sp.arm_length = arm.length;
  sp.arm_inclination = theta;
  const double t = std::tan(theta);
  sp.arm_wire_lateral_stiffness = wire.stiffness;
  sp.arm_pull_off = pull_off;
  sp.arm_pull_side = wire.side;
  sp.stiffness = pull_off / (arm.length * c * c * c) + wire.stiffness * t * t;
  if (in_plan) {
    sp.arm_lateral_share = wire.stiffness * t * t;
    sp.stiffness -= sp.arm_lateral_share;
  }
  sp.arm_tip_mass = arm.tip_mass() / (c * c);
}

}  // namespace

void design_statics(const Scene& scene, const std::vector<std::vector<double>>& section_supports, Model& m) {
  // Design statics, section by section. Each contact wire is held at its supports (raised by d at
  // the outer support of a transition span) and, at every dropper, at the presag height of a
  // current span or at the working height in a transition span (where the free wire then rises
  // from its last dropper to the raised support, Fig. 2); the reactions there are the dropper
  // tensions. The messenger carries those tensions and the dropper weight to its supports. The
  // dropper weight depends on its length, which depends on the messenger sag: a few fixed-point
  // passes settle it. On a compound line the contact wire is held so at its hangers, the
  // auxiliary messenger at its droppers (AuxiliaryMessengerSpec::height above the contact wire),
  // and the messenger carries the droppers.
  std::vector<double> weight_len(m.droppers.size(), scene.encumbrance);  // lengths the weights use
  for (std::size_t k = 0; k < m.droppers.size(); ++k)  // a compound line's: the auxiliary's height
    if (const auto& aux = scene.sections[m.droppers[k].section].auxiliary_messenger)
      weight_len[k] = m.droppers[k].hanger ? aux->height : scene.encumbrance - aux->height;
  std::vector<double> dropper_len = weight_len;                          // geometric lengths
  std::vector<std::vector<double>> react(m.wires.size());
  for (std::size_t si = 0; si < scene.sections.size(); ++si)
    section_statics(scene, si, section_supports, m, weight_len, dropper_len, react);
  set_dropper_lengths(scene, weight_len, dropper_len, m);
  // Support preloads f0 of eq. 4: the static reactions at the elastic supports.
  std::vector<int> hinged;  // springs that are hinged arms, and their nodes
  std::vector<int> hinged_dofs;
  for (std::size_t k = 0; k < m.springs.size(); ++k) {
    SupportSpring& sp = m.springs[k];
    const Wire& w = wire_of(m, sp.dof);
    sp.static_force = react[&w - m.wires.data()][sp.section_support];
    const std::optional<SupportSpec>& arm = scene.sections[w.section].steady_arms;
    if (sp.steady_arm && arm && arm->hinged_arm) {
      hinged.push_back(static_cast<int>(k));
      hinged_dofs.push_back(sp.dof);
    }
  }
  if (hinged.empty()) return;
  const std::vector<RegistrationLateral> wire = registration_lateral(m, hinged_dofs);
  for (std::size_t q = 0; q < hinged.size(); ++q) {
    SupportSpring& sp = m.springs[hinged[q]];
    const int section = wire_of(m, sp.dof).section;
    const HingedArmSpec& arm = *scene.sections[section].steady_arms->hinged_arm;
    // (The arms a 3-D line's lateral plane moves: pulled to one side, LateralModel::registrations.)
    const bool in_plan = scene.lateral() && wire[q].side != 0.0;
    set_hinged_arm(arm, scene.gravity, wire[q], scene.section_field(section, "steady_arms"), in_plan, sp);
    // The tip's sideways share of inertia: mass without weight, so the preload carries it too.
    const double sideways = sp.arm_tip_mass - arm.tip_mass();
    m.mass[sp.dof] += sideways;
    sp.static_force += sideways * scene.gravity;
  }
}

}  // namespace catenary_sim
