// The scene's own methods: lengths, limits and profiles computed from the plain data. Reading the
// YAML is read_scene.cpp (and the rooms' readers beside it), checking it validate_scene.cpp.
#include "catenary_sim/core/scene/scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace catenary_sim {

double SectionSpec::length() const {
  double l = 0.0;
  for (double x : spans) l += x;
  return l;
}

std::string TrainSpeedLimit::text() const {
  std::ostringstream s;
  s.precision(4);
  if (below_wave_speed)
    s << "0 to below " << max << " m/s (" << max * 3.6 << " km/h), the contact wire's wave speed c = sqrt(T / rhoA): "
      << "a faster pass is supercritical (the wire's wave cannot run ahead of the pantograph), outside what the model "
         "covers; numerics.allow_supercritical: true runs it anyway";
  else
    s << "0 to " << max << " m/s (" << max * 3.6 << " km/h)";
  return s.str();
}

TrainSpeedLimit train_speed_limit(const Scene& scene) {
  TrainSpeedLimit l;
  l.wave_speed = std::numeric_limits<double>::infinity();
  for (const SectionSpec& sec : scene.sections)
    if (sec.contact_wire.linear_mass > 0.0 && !sec.rigid)  // a profile without tension has no string wave
      l.wave_speed = std::min(l.wave_speed, std::sqrt(sec.contact_wire.tension / sec.contact_wire.linear_mass));
  l.below_wave_speed = !scene.numerics.allow_supercritical && l.wave_speed <= kMaxTrainSpeed;
  l.max = l.below_wave_speed ? l.wave_speed : kMaxTrainSpeed;
  return l;
}

bool transition_piece_at_start(const Scene& scene, std::size_t i) {
  return scene.sections[i].rail_transition_piece && i > 0 && !scene.sections[i - 1].rigid;
}

bool transition_piece_at_end(const Scene& scene, std::size_t i) {
  return scene.sections[i].rail_transition_piece && i + 1 < scene.sections.size() && !scene.sections[i + 1].rigid;
}

double wind_field_points(const Scene& scene) {
  if (!scene.wind || !scene.wind->turbulence) return 0.0;
  // The stretch whose points the field holds at once: a finite line's whole length; an endless
  // line generates its points as the block moves and holds the block's only, a block of spans
  // around the train and the lateral plane's gust lead, at most kMaxGustLead s of travel at the
  // speed ceiling (the block's exact length is the model's).
  double reach = scene.line_length();
  if (scene.endless) reach = 16.0 * scene.spans.front() + kMaxGustLead * kMaxTrainSpeed;
  return std::ceil(reach / scene.wind->turbulence->spacing) + 1.0;
}

double Scene::line_length() const {
  double s = 0.0;
  for (double l : spans) s += l;
  return s;
}

std::string Scene::section_field(std::size_t i, const std::string& name) const {
  if (sections.size() < 2) return name;
  const std::vector<std::string>& given = sections[i].given;
  const std::string part = name.substr(0, name.find('.'));
  if (!given.empty() && std::find(given.begin(), given.end(), part) == given.end()) return name;
  return "sections[" + std::to_string(i) + "]." + name;
}

int Scene::analysis_first() const {
  const int n = static_cast<int>(spans.size());
  return output.analysis_first_span ? *output.analysis_first_span : (n > 4 ? 2 : 0);
}

int Scene::analysis_last() const {
  const int n = static_cast<int>(spans.size());
  return output.analysis_last_span ? *output.analysis_last_span : (n > 4 ? n - 2 : n);
}

double LineProfile::at(double x) const {
  if (stations.empty() || x < stations.front() || x > stations.back()) return 0.0;
  const auto it = std::upper_bound(stations.begin(), stations.end(), x);
  if (it == stations.end()) return values.back();
  const std::size_t j = static_cast<std::size_t>(it - stations.begin());
  const double t = (x - stations[j - 1]) / (stations[j] - stations[j - 1]);
  return values[j - 1] + t * (values[j] - values[j - 1]);
}

double PantographHeadSpec::sway(double t) const {
  if (sway_times.empty()) return sway_amplitude * std::sin(2.0 * M_PI * sway_frequency * t);
  if (t <= sway_times.front()) return sway_lateral.front();
  if (t >= sway_times.back()) return sway_lateral.back();
  const std::size_t k = std::upper_bound(sway_times.begin(), sway_times.end(), t) - sway_times.begin();
  const double a = (t - sway_times[k - 1]) / (sway_times[k] - sway_times[k - 1]);
  return sway_lateral[k - 1] + a * (sway_lateral[k] - sway_lateral[k - 1]);
}

}  // namespace catenary_sim
