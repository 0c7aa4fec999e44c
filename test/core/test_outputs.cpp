// The pure output functions against published and analytic values: rainflow on the worked example
// of ASTM E1049-85, Welch on a sum of sines, contact-loss events on a series built by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <vector>

#include "catenary_sim/core/output/elasticity_uniformity.hpp"
#include "catenary_sim/core/output/line_measures.hpp"

using namespace catenary_sim;

namespace {

// ASTM E1049-85 (reapproved 2017), "Standard Practices for Cycle Counting in Fatigue Analysis",
// section 5.4.4 rainflow counting, Fig. 6: the load history -2, 1, -3, 5, -1, 3, -4, 4, -2 and its
// published counts (Table 4 / Fig. 6(f)): range 3: 0.5 cycle, 4: 1.5, 6: 0.5, 8: 1.0, 9: 0.5.
TEST(Rainflow, AstmE1049WorkedExample) {
  const std::vector<double> history{-2, 1, -3, 5, -1, 3, -4, 4, -2};
  const std::vector<RainflowCycle> cycles = rainflow(history);
  std::map<double, double> counts;
  for (const RainflowCycle& c : cycles) counts[c.range] += c.count;
  const std::map<double, double> published{{3, 0.5}, {4, 1.5}, {6, 0.5}, {8, 1.0}, {9, 0.5}};
  EXPECT_EQ(counts, published);  // exact: small integers, only |a - b| and halves
  // The full cycle of range 4 is the one from -1 to 3 (Fig. 6(c)): mean 1.
  bool full = false;
  for (const RainflowCycle& c : cycles)
    if (c.count == 1.0 && c.range == 4.0) full = c.mean == 1.0;
  EXPECT_TRUE(full);
}

TEST(Rainflow, TurningPointsReduceARawSeriesToTheExample) {
  // The example's history sampled with intermediate points and repeated values: the same reversals.
  const std::vector<double> raw{-2, -1, 0, 1, 1, -3, 0, 2, 5, 5, 4, -1, 3, 0, -4, 4, 3, -2};
  EXPECT_EQ(turning_points(raw), (std::vector<double>{-2, 1, -3, 5, -1, 3, -4, 4, -2}));
  EXPECT_TRUE(turning_points({}).empty());
  EXPECT_EQ(turning_points({2, 2, 2}), std::vector<double>{2});
}

TEST(Rainflow, HistogramBinsByRangeAndKeepsHalfCycles) {
  const std::vector<RainflowCycle> cycles = rainflow({-2, 1, -3, 5, -1, 3, -4, 4, -2});
  // Bins of width 2 over [0, 10]: ranges 3 | 4 | 6 | 8, 9 -> bins 1, 2, 3, 4.
  const std::vector<double> h = rainflow_histogram(cycles, 10.0, 5);
  EXPECT_EQ(h, (std::vector<double>{0.0, 0.5, 1.5, 0.5, 1.5}));
  // A range above the top is left out; the top itself is in the last bin.
  EXPECT_EQ(rainflow_histogram(cycles, 8.0, 4), (std::vector<double>{0.0, 0.5, 1.5, 1.5}));
}

// Two sines off the frequency grid plus an offset: Welch finds both frequencies, their amplitudes
// and (Parseval) the variance.
TEST(Welch, SumOfSinesRecoversFrequenciesAndAmplitudes) {
  const double fs = 1000.0, a1 = 3.0, f1 = 7.3, a2 = 1.5, f2 = 23.1;
  std::vector<double> x(20000);
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double t = i / fs;
    x[i] = 2.0 + a1 * std::sin(2 * M_PI * f1 * t) + a2 * std::sin(2 * M_PI * f2 * t + 0.4);
  }
  const Spectrum s = welch_psd(x, fs, 4000);
  EXPECT_EQ(s.segment, 4000u);
  EXPECT_EQ(s.segments, 9u);  // (20000 - 4000) / 2000 + 1
  EXPECT_DOUBLE_EQ(s.resolution, 0.25);
  ASSERT_EQ(s.frequency.size(), 4096u / 2 + 1);
  // Parseval: the PSD integrates to the variance a1^2/2 + a2^2/2 = 5.625. The Welch estimate of a
  // sine's power is exact up to the leakage of the segments' non-integer periods, which the
  // Hann window keeps to a few 1e-4 of the power: 0.5 % is ample and would catch a wrong scale
  // (a factor 2 for one-sided, or the window's sum instead of its energy, are 50 % or more).
  double power = 0.0;
  for (double p : s.psd) power += p * (s.frequency[1] - s.frequency[0]);
  EXPECT_NEAR(power, 0.5 * a1 * a1 + 0.5 * a2 * a2, 0.005 * 5.625);
  const std::vector<SpectralPeak> peaks = spectral_peaks(s, 1.0, 100.0, 5);
  ASSERT_GE(peaks.size(), 2u);
  // Strongest first; each within half a grid step (fs / nfft = 0.244 Hz) of the true frequency.
  const double grid = s.frequency[1];
  EXPECT_NEAR(peaks[0].frequency, f1, 0.5 * grid + 1e-12);
  EXPECT_NEAR(peaks[1].frequency, f2, 0.5 * grid + 1e-12);
  // Amplitude from the power within +-3 resolutions: the Hann main lobe (+-2) holds all but a
  // fraction of a percent of a sine's power; 2 % tolerance.
  EXPECT_NEAR(peaks[0].amplitude, a1, 0.02 * a1);
  EXPECT_NEAR(peaks[1].amplitude, a2, 0.02 * a2);
  // Everything else is leakage, orders of magnitude weaker.
  for (std::size_t i = 2; i < peaks.size(); ++i) EXPECT_LT(peaks[i].psd, 1e-3 * peaks[1].psd);
}

TEST(Welch, ShortSeriesIsOneSegmentAndEmptyIsEmpty) {
  std::vector<double> x(300, 1.0);
  const Spectrum s = welch_psd(x, 100.0, 1000);
  EXPECT_EQ(s.segment, 300u);
  EXPECT_EQ(s.segments, 1u);
  for (double p : s.psd) EXPECT_EQ(p, 0.0);  // a constant has no variance once the mean is removed
  EXPECT_TRUE(welch_psd({}, 100.0, 10).psd.empty());
}

// A series built by hand: t_i = 0.01 i s, x_i = 100 + 2 i m, with force 0 at samples 5-7, 20,
// 45-52 (crossing the section's end at x = 200, sample 50) and 60 (outside).
TEST(ContactLoss, EventsDetectedExactly) {
  std::vector<double> t, x, f;
  for (int i = 0; i < 70; ++i) {
    t.push_back(0.01 * i);
    x.push_back(100.0 + 2.0 * i);
    const bool lost = (i >= 5 && i <= 7) || i == 20 || (i >= 45 && i <= 52) || i == 60;
    f.push_back(lost ? (i == 6 ? -0.0 : 0.0) : 120.0 + i);
  }
  // Section [104, 200]: samples 2..50.
  const std::vector<ContactLossEvent> ev = contact_loss_events(t, x, f, 104.0, 200.0);
  ASSERT_EQ(ev.size(), 3u);
  EXPECT_DOUBLE_EQ(ev[0].start_time, 0.05);
  EXPECT_DOUBLE_EQ(ev[0].station, 110.0);
  EXPECT_NEAR(ev[0].duration, 0.03, 1e-12);  // samples 5, 6, 7; contact again at 8 (rounding of 0.01 i only)
  EXPECT_DOUBLE_EQ(ev[0].length, 6.0);
  EXPECT_DOUBLE_EQ(ev[1].start_time, 0.2);
  EXPECT_NEAR(ev[1].duration, 0.01, 1e-12);
  EXPECT_DOUBLE_EQ(ev[1].station, 140.0);
  // Cut at the section's end: sample 50 (x = 200) is the last inside, 51 outside ends it.
  EXPECT_DOUBLE_EQ(ev[2].start_time, 0.45);
  EXPECT_NEAR(ev[2].duration, 0.06, 1e-12);
  EXPECT_DOUBLE_EQ(ev[2].length, 12.0);
  // A loss that lasts to the last sample stands for one period; none at all: no event.
  const std::vector<ContactLossEvent> tail = contact_loss_events(t, x, f, 205.0, 220.0);  // samples 53..60
  ASSERT_EQ(tail.size(), 1u);
  EXPECT_DOUBLE_EQ(tail[0].start_time, 0.6);
  EXPECT_NEAR(tail[0].duration, 0.01, 1e-12);
  EXPECT_TRUE(contact_loss_events(t, x, std::vector<double>(70, 1.0), 0.0, 1e9).empty());
}

}  // namespace

// The elasticity's uniformity per span on a curve known in closed form: e = e0 (1 + sin^2(pi s /
// L)) over each span of L = 10 m, sampled every 0.5 m (the supports and mid-spans among the
// samples), so min e0, max 2 e0, mean 1.5 e0 (the samples of sin^2 over a period average 1/2
// exactly), U = (2 - 1) / (2 + 1) = 1/3. A sample without a value (the probe not touching) is
// skipped; a span with fewer than two samples is left out.
TEST(ElasticityUniformity, PerSpanRangeAndUniformityOfAKnownCurve) {
  const double e0 = 1e-4, L = 10.0;
  std::vector<double> x, e;
  for (int i = 0; i <= 40; ++i) {
    x.push_back(0.5 * i);
    const double s = std::sin(M_PI * x.back() / L);
    e.push_back(e0 * (1.0 + s * s));
  }
  e[5] = std::nan("");  // 2.5 m: no value there
  const std::vector<catenary_sim::SpanElasticity> spans = catenary_sim::elasticity_by_span(x, e, {0.0, 10.0, 20.0, 20.2});
  ASSERT_EQ(spans.size(), 2u);  // the 0.2 m span holds one sample (20 m)
  for (const auto& s : spans) {
    EXPECT_NEAR(s.min, e0, 1e-15);
    EXPECT_NEAR(s.max, 2.0 * e0, 1e-15);
    EXPECT_NEAR(s.uniformity, 1.0 / 3.0, 1e-12);
  }
  EXPECT_EQ(spans[0].samples, 20);  // 21 stations in [0, 10] less the one without a value
  EXPECT_EQ(spans[1].samples, 21);
  EXPECT_NEAR(spans[1].mean, 1.5 * e0 * 20.0 / 21.0 + e0 / 21.0, 1e-15);  // 20 samples of a period, plus one support
}
