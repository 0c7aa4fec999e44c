#include "model/imperfections.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "catenary_sim/core/model/beam.hpp"
#include "catenary_sim/core/model/wire_band.hpp"
#include "model/normal_errors.hpp"
#include "util/format.hpp"

namespace catenary_sim {

namespace {

// Spectral representation of a random profile (Shinozuka): sum_j a_j cos(k_j x + phi_j) with the
// one-sided power-law spectrum S(k) ~ k^-n shared among kHarmonics bands equally spaced in log k
// between 2 pi / wavelength_max and 2 pi / wavelength_min, a_j^2 / 2 = S(k_j) dk_j scaled so that
// sum a_j^2 / 2 = rms^2; each k_j drawn inside its band (no common period) and each phase uniform.
std::vector<double> irregularity_profile(const IrregularitySpec& ir, NormalErrors& gen, const std::vector<Wire>& wires) {
  std::vector<double> out;
  if (!ir.profile.empty()) {
    for (const Wire& w : wires)
      if (w.is_contact_wire)
        for (double x : w.x) out.push_back(ir.profile.at(x));
    return out;
  }
  constexpr int kHarmonics = 256;
  const double k0 = 2.0 * M_PI / ir.wavelength_max, k1 = 2.0 * M_PI / ir.wavelength_min;
  const double step = std::log(k1 / k0) / kHarmonics;
  std::vector<double> k(kHarmonics), a(kHarmonics), phase(kHarmonics);
  double power = 0.0;
  for (int j = 0; j < kHarmonics; ++j) {
    const double lo = k0 * std::exp(j * step), hi = k0 * std::exp((j + 1) * step);
    k[j] = lo + (hi - lo) * gen.uniform();
    phase[j] = 2.0 * M_PI * gen.uniform();
    a[j] = std::pow(0.5 * (lo + hi), -ir.exponent) * (hi - lo);  // S(k_j) dk_j, scaled below
    power += a[j];
  }
  for (double& aj : a) aj = std::sqrt(2.0 * aj / power) * ir.rms;
  for (const Wire& w : wires) {
    if (!w.is_contact_wire) continue;
    for (double x : w.x) {
      double r = 0.0;
      for (int j = 0; j < kHarmonics; ++j) r += a[j] * std::cos(k[j] * x + phase[j]);
      out.push_back(r);
    }
  }
  return out;
}

}  // namespace

// The line as built: the design statics set the dropper lengths and support heights; the errors
// act on the built line through the constant load (at u = 0 it no longer balances, and the eq. 23
// statics find where the built line hangs). A dropper longer by e carries k e less at the design
// geometry; a steady arm assembled e higher pushes k_A e more (eq. 4 with y0 + e); a point mass
// adds its mass and weight to the nearest contact-wire node.
void apply_imperfections(const Scene& scene, Model& m, const std::vector<bool>& fixed) {
  const ImperfectionSpec& im = scene.imperfections;
  if (!im.any()) return;
  NormalErrors shared(im.seed);
  NormalErrors own_droppers(im.dropper_length_seed.value_or(0)), own_arms(im.support_height_seed.value_or(0));
  NormalErrors& dropper_normal = im.dropper_length_seed ? own_droppers : shared;
  NormalErrors& arm_normal = im.support_height_seed ? own_arms : shared;
  std::vector<int> order(m.droppers.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = static_cast<int>(k);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return m.droppers[a].x < m.droppers[b].x; });
  if (!im.dropper_length_errors.empty() && im.dropper_length_errors.size() != order.size())
    throw SceneError("scene field 'imperfections.dropper_length_errors' = (" + std::to_string(im.dropper_length_errors.size()) +
                     " values): one per dropper in line order (" + std::to_string(order.size()) + ")");
  if ((im.dropper_length_std > 0.0 || !im.dropper_length_errors.empty()) && order.empty())
    throw SceneError("scene field 'imperfections.dropper_length_std': the scene has no droppers");
  for (std::size_t j = 0; j < order.size(); ++j) {
    const double e = !im.dropper_length_errors.empty() ? im.dropper_length_errors[j]
                     : im.dropper_length_std > 0.0     ? dropper_normal.next(im.dropper_length_std)
                                                       : 0.0;
    Dropper& d = m.droppers[order[j]];
    if (e >= d.unstretched_length) {
      // Named as given: a listed error, or the draw of dropper_length_std (a compound line's hangers draw too).
      const char* part = d.hanger ? "hanger" : "dropper";
      if (!im.dropper_length_errors.empty())
        throw SceneError("scene field 'imperfections.dropper_length_errors' (the " + std::string(part) + " at " + fmt(d.x) +
                         " m) = " + fmt_given(e) + ": allowed below its length " + fmt(d.unstretched_length) + " m");
      throw SceneError("scene field 'imperfections.dropper_length_std' = " + fmt_given(im.dropper_length_std) + " m draws " +
                       fmt(e) + " m for the " + part + " at " + fmt(d.x) + " m, not below its length " +
                       fmt(d.unstretched_length) + " m: a smaller spread, or another dropper_length_seed");
    }
    d.static_tension -= d.stiffness * e;  // may go negative: a dropper too long hangs slack
  }
  std::vector<int> arms;
  for (std::size_t k = 0; k < m.springs.size(); ++k)
    if (m.springs[k].steady_arm) arms.push_back(static_cast<int>(k));
  std::stable_sort(arms.begin(), arms.end(), [&](int a, int b) { return m.springs[a].x < m.springs[b].x; });
  if (!im.support_height_errors.empty() && im.support_height_errors.size() != arms.size())
    throw SceneError("scene field 'imperfections.support_height_errors' = (" + std::to_string(im.support_height_errors.size()) +
                     " values): one per steady arm in line order (" + std::to_string(arms.size()) + ")");
  if ((im.support_height_std > 0.0 || !im.support_height_errors.empty()) && arms.empty())
    throw SceneError("scene field 'imperfections.support_height_std': the scene has no steady arms (elastic contact-wire "
                     "supports; rigid supports cannot be displaced)");
  for (std::size_t j = 0; j < arms.size(); ++j) {
    const double e = !im.support_height_errors.empty() ? im.support_height_errors[j]
                     : im.support_height_std > 0.0     ? arm_normal.next(im.support_height_std)
                                                       : 0.0;
    m.load[m.springs[arms[j]].dof] += m.springs[arms[j]].static_stiffness() * e;
  }
  const double g = scene.gravity;
  const IrregularitySpec& ir = im.contact_wire_irregularity;
  if (ir.any()) {
    NormalErrors own_irregularity(ir.seed.value_or(0));
    const std::vector<double> r = irregularity_profile(ir, ir.seed ? own_irregularity : shared, m.wires);
    std::size_t at = 0;
    for (Wire& w : m.wires) {
      if (!w.is_contact_wire) continue;
      for (int i = 0; i < w.nodes(); ++i) w.height[i] += r[at++];
    }
  }
  for (const PointMassSpec& pm : im.point_masses) {
    const Wire& w = m.wires[m.contact_wires.front()];
    const auto it = std::lower_bound(w.x.begin(), w.x.end(), pm.station);
    int node = static_cast<int>(it - w.x.begin());
    if (node == w.nodes() || (node > 0 && pm.station - w.x[node - 1] < w.x[node] - pm.station)) --node;
    const int dof = w.w_dof + node;
    if (fixed[dof]) continue;  // on a rigid support: held, no dynamic effect
    m.mass[dof] += pm.mass;
    m.load[dof] -= g * pm.mass;
  }
}

void apply_wear(const Scene& scene, Model& m) {
  const bool lumped_rot = scene.numerics.rotary_inertia == RotaryInertia::kLumped;
  // Wear (the line as built, after the design statics): a worn contact wire element is lighter
  // and bends more easily; the constant load below then no longer balances at u = 0, and the
  // eq. 23 statics find where the worn line hangs.
  const WearSpec& wear = scene.imperfections.contact_wire_wear;
  if (wear.any())
    for (Wire& w : m.wires) {
      if (!w.is_contact_wire) continue;
      std::vector<double> ei_factor(w.nodes() - 1, 1.0);
      for (int e = 0; e + 1 < w.nodes(); ++e) {
        const double loss = wear.at(0.5 * (w.x[e] + w.x[e + 1])), he = w.x[e + 1] - w.x[e];
        ei_factor[e] = std::pow(1.0 - loss, wear.ei_exponent);
        m.mass[w.w_dof + e] -= loss * beam_translational_mass(he, w.spec.linear_mass);
        m.mass[w.w_dof + e + 1] -= loss * beam_translational_mass(he, w.spec.linear_mass);
        if (lumped_rot) {
          m.mass[w.theta_dof + e] -= loss * beam_rotary_mass(he, w.spec.linear_mass);
          m.mass[w.theta_dof + e + 1] -= loss * beam_rotary_mass(he, w.spec.linear_mass);
        }
      }
      assemble_band(w, ei_factor);
    }
}

}  // namespace catenary_sim
