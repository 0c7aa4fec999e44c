#include "catenary_sim/core/output/elasticity_uniformity.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace catenary_sim {

std::vector<SpanElasticity> elasticity_by_span(const std::vector<double>& x, const std::vector<double>& e,
                                               const std::vector<double>& supports) {
  std::vector<SpanElasticity> out;
  const std::size_t n = std::min(x.size(), e.size());
  for (std::size_t i = 0; i + 1 < supports.size(); ++i) {
    SpanElasticity s;
    s.span = static_cast<int>(i);
    s.start = supports[i];
    s.end = supports[i + 1];
    double sum = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      if (x[k] < s.start - 1e-9 || x[k] > s.end + 1e-9 || !std::isfinite(e[k])) continue;
      s.min = s.samples == 0 ? e[k] : std::min(s.min, e[k]);
      s.max = s.samples == 0 ? e[k] : std::max(s.max, e[k]);
      sum += e[k];
      ++s.samples;
    }
    if (s.samples < 2) continue;
    s.mean = sum / s.samples;
    s.uniformity = s.max + s.min > 0.0 ? (s.max - s.min) / (s.max + s.min) : 0.0;
    out.push_back(s);
  }
  return out;
}

}  // namespace catenary_sim
