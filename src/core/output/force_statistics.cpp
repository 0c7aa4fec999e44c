#include "catenary_sim/core/output/force_statistics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace catenary_sim {

ForceStatistics force_statistics(const std::vector<double>& x) {
  ForceStatistics s;
  if (x.empty()) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    s.mean = s.std_dev = s.max = s.min = s.stat_max = s.stat_min = nan;
    return s;
  }
  double sum = 0.0;
  s.max = -std::numeric_limits<double>::infinity();
  s.min = std::numeric_limits<double>::infinity();
  for (double v : x) {
    sum += v;
    s.max = std::max(s.max, v);
    s.min = std::min(s.min, v);
  }
  s.mean = sum / x.size();
  double var = 0.0;
  for (double v : x) var += (v - s.mean) * (v - s.mean);
  s.std_dev = std::sqrt(var / x.size());
  s.stat_max = s.mean + 3.0 * s.std_dev;
  s.stat_min = s.mean - 3.0 * s.std_dev;
  return s;
}

std::optional<PantographStatistics::TargetMean> target_mean(const std::optional<TargetMeanForce>& target, double v,
                                                            double mean) {
  if (!target || !std::isfinite(v) || !std::isfinite(mean)) return std::nullopt;
  PantographStatistics::TargetMean t;
  t.speed_mps = v;
  t.target = target->at(v);
  t.difference = mean - t.target;
  t.tolerance = target->tolerance;
  t.within = !t.tolerance || std::fabs(t.difference) <= *t.tolerance;
  return t;
}

}  // namespace catenary_sim
