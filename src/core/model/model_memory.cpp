// The model's memory, estimated from the scene before anything is allocated, and a pass's steps.
#include "catenary_sim/core/model/model_memory.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/model/wind_field.hpp"

namespace catenary_sim {

double model_memory_limit_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return 8.0 * (1ull << 30);  // unknown: assume a small 16 GiB machine
  return 0.5 * static_cast<double>(pages) * static_cast<double>(page);
}

double estimate_model_bytes(const Scene& scene) {
  double nodes = 0.0;
  const double h = scene.numerics.element_length;
  for (const SectionSpec& sec : scene.sections) {
    double droppers = 0.0;
    for (const std::optional<DropperSpec>* part : {&sec.droppers, &sec.hangers})  // (a compound line's hangers are nodes too)
      if (*part)
        for (const auto& span : (*part)->positions) droppers += static_cast<double>(span.size());
    // A stitch wire's two clamps are nodes of every wire of its section; the stitch wires together
    // are shorter than the section, so they count as one more wire at most.
    const double clamps = sec.stitch_wire ? 2.0 * static_cast<double>(sec.spans.size()) : 0.0;
    const double per_wire = std::ceil(sec.length() / h) + droppers + clamps + static_cast<double>(sec.spans.size()) + 1.0;
    const double wires =
        sec.contact_wire_count + (sec.messenger ? 1 : 0) + (sec.stitch_wire ? 1 : 0) + (sec.auxiliary_messenger ? 1 : 0);
    nodes += wires * per_wire;
  }
  return kModelBytesPerNode * nodes + estimate_wind_field_bytes(scene);
}

double estimate_wind_field_bytes(const Scene& scene) {
  // The turbulent wind's series (wind_field.hpp): a finite line's every point, once in the model; an
  // endless line's block, in the pass's initial state and its running state.
  if (!scene.wind || !scene.wind->turbulence) return 0.0;
  return (scene.endless ? 2.0 : 1.0) * wind_field_bytes_estimate(*scene.wind, scene.line_length());
}

void check_model_memory(const Scene& scene) {
  const double need = estimate_model_bytes(scene), limit = model_memory_limit_bytes();
  if (need > limit) {
    std::ostringstream s;
    s.precision(3);
    const double wind = estimate_wind_field_bytes(scene);
    s << "scene: the model would need about " << need / (1ull << 30) << " GiB (" << scene.line_length() / 1000.0
      << " km of line in " << scene.numerics.element_length << " m elements";
    if (wind > 0.0)
      s << ", " << wind / (1ull << 30) << " GiB of it the turbulent wind's " << wind_field_points(scene)
        << " points, wind.turbulence.spacing " << scene.wind->turbulence->spacing << " m apart";
    s << "), more than the limit of " << limit / (1ull << 30) << " GiB (half of this machine's memory); ";
    if (wind > 0.5 * need)
      s << "use a longer wind.turbulence.spacing or a lower wind.turbulence.max_frequency";
    else
      s << "use a longer numerics.element_length, fewer or shorter spans (line.span_count, line.span_length), or "
           "line.endless with numerics.window";
    throw SceneError(s.str());
  }
}

double pass_distance(const Model& m) {
  return m.train_end - m.train_start - (m.endless ? m.initial_line_offset : 0.0);
}

double pass_step_count(const Model& m) {
  const double v = m.scene.train_speed;
  if (!(v > 0.0)) return std::numeric_limits<double>::infinity();
  return std::max(0.0, pass_distance(m)) / v / m.dt;
}

}  // namespace catenary_sim
