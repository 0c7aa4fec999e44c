#include "catenary_sim/hil/latency.hpp"

#include <algorithm>
#include <cmath>

namespace catenary_sim {
namespace hil {

namespace {

constexpr double kBinWidth = 1e-6;    // s
constexpr std::size_t kBins = 10000;  // up to 10 ms

}  // namespace

LatencyHistogram::LatencyHistogram() : bins_(kBins, 0) {}

void LatencyHistogram::add(double s) {
  if (!std::isfinite(s)) return;
  s = std::max(0.0, s);
  const std::size_t b = std::min(kBins - 1, static_cast<std::size_t>(s / kBinWidth));
  ++bins_[b];
  ++count_;
  sum_ += s;
  max_ = std::max(max_, s);
}

double LatencyHistogram::quantile(double q) const {
  if (count_ == 0) return 0.0;
  const double target = std::clamp(q, 0.0, 1.0) * static_cast<double>(count_);
  std::uint64_t cum = 0;
  for (std::size_t b = 0; b < kBins; ++b) {
    cum += bins_[b];
    if (static_cast<double>(cum) >= target && cum > 0)
      return b + 1 == kBins ? max_ : std::min(max_, (b + 1) * kBinWidth);  // (the last bin: beyond 10 ms)
  }
  return max_;
}

std::vector<std::uint64_t> LatencyHistogram::coarse(double width) const {
  const std::size_t per = std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(width / kBinWidth)));
  std::vector<std::uint64_t> out((kBins + per - 1) / per, 0);
  for (std::size_t b = 0; b < kBins; ++b) out[b / per] += bins_[b];
  while (!out.empty() && out.back() == 0) out.pop_back();
  return out;
}

std::uint64_t LatencyHistogram::count_below(double s) const {
  const std::size_t end = std::min(kBins, static_cast<std::size_t>(std::llround(std::max(0.0, s) / kBinWidth)));
  std::uint64_t n = 0;
  for (std::size_t b = 0; b < end; ++b) n += bins_[b];
  return n;
}

void LatencyHistogram::clear() {
  std::fill(bins_.begin(), bins_.end(), 0);
  count_ = 0;
  max_ = sum_ = 0.0;
}

JitterSummary summarize_jitter(const LatencyHistogram& h) {
  JitterSummary j;
  j.p50 = h.quantile(0.5);
  j.p99 = h.quantile(0.99);
  j.max = h.max();
  std::uint64_t below = 0;
  for (std::size_t i = 0; i < JitterSummary::kEdges.size(); ++i) {
    const std::uint64_t n = h.count_below(JitterSummary::kEdges[i]);
    j.counts[i] = n - below;
    below = n;
  }
  j.counts.back() = h.count() - below;
  return j;
}

}  // namespace hil
}  // namespace catenary_sim
