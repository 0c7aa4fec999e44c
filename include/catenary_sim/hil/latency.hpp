// The HIL loop's timing statistics: latencies in a fixed histogram (no allocation in the loop)
// and the jitter summary the diagnostics show.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace catenary_sim {
namespace hil {

// Latencies (s) in 1 us bins up to 10 ms (longer ones count in the last bin and in max()).
// Fixed size: add() never allocates.
class LatencyHistogram {
 public:
  LatencyHistogram();
  void add(double seconds);
  std::uint64_t count() const { return count_; }
  double max() const { return max_; }
  double mean() const { return count_ ? sum_ / count_ : 0.0; }
  // q in [0, 1]: the upper edge of the bin holding the q-quantile (0 when empty).
  double quantile(double q) const;
  // Counts per bin of `width` s (a multiple of 1 us) up to the last non-empty one: a histogram to
  // print or write (the last bin also holds everything beyond 10 ms).
  std::vector<std::uint64_t> coarse(double width) const;
  // Samples below `seconds` (to the microsecond).
  std::uint64_t count_below(double seconds) const;
  void clear();

 private:
  std::vector<std::uint64_t> bins_;
  std::uint64_t count_ = 0;
  double max_ = 0.0, sum_ = 0.0;
};

// The loop's jitter for diagnostics: percentiles and counts between fixed edges.
struct JitterSummary {
  static constexpr std::array<double, 7> kEdges{10e-6, 20e-6, 50e-6, 100e-6, 200e-6, 500e-6, 1e-3};  // s
  static constexpr std::array<const char*, 8> kLabels{"< 10 us",    "10-20 us",   "20-50 us", "50-100 us",
                                                      "100-200 us", "200-500 us", "0.5-1 ms", ">= 1 ms"};
  double p50 = 0.0, p99 = 0.0, max = 0.0;
  std::array<std::uint64_t, 8> counts{};  // [0, 10 us), [10, 20 us), ..., [0.5, 1 ms), >= 1 ms
};
JitterSummary summarize_jitter(const LatencyHistogram& h);

}  // namespace hil
}  // namespace catenary_sim
