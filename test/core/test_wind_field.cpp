// The turbulent wind field (wind_field.hpp): its spectrum as the wires feel it, and its memory on a
// line that runs on.
#include <gtest/gtest.h>

#include <unsupported/Eigen/FFT>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <complex>
#include <vector>

#include "catenary_sim/core/model/lateral.hpp"
#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/model/wind_field.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

using test_scenes::gusty_wind;

TEST(WindField, SpectrumAsTheWiresFeelItIsVonKarmansUpToMaxFrequency) {
  // The field at a point sampled as the wires take it (refreshed every 0.01 s, the refresh of
  // lateral.cpp at the default 5 Hz), Welch's estimate of its one-sided PSD (Hann window, 1024
  // samples = 10.24 s, no overlap, the segment mean removed) averaged over segments, over points
  // 100 m apart (Davenport's coherence exp(-C f dx / U) is e^-75 at 1.5 Hz: independent) and over
  // two seeds, against von Karman's spectrum in bands of 5 bins around 1.5-4.5 Hz (the Hann
  // window's main lobe, +-0.2 Hz, would reach past the band's top at 5 Hz above that).
  const double fs = 100.0;
  const int seg = 1024;
  const std::vector<double> centres = {1.5, 2.0, 3.0, 4.0, 4.5};
  const int half_band = 2;
  const double df = fs / seg;
  std::vector<double> window(seg), psd(seg / 2 + 1, 0.0);
  double w2 = 0.0;
  for (int n = 0; n < seg; ++n) {
    window[n] = 0.5 - 0.5 * std::cos(2.0 * M_PI * n / seg);
    w2 += window[n] * window[n];
  }
  Eigen::FFT<double> fft;
  std::vector<double> x(seg);
  std::vector<std::complex<double>> X;
  long segments = 0;
  const WindSpec first = gusty_wind(21);
  const double U = first.speed, sigma = first.turbulence->intensity * U, L = first.turbulence->length_scale;
  for (std::uint64_t seed : {21u, 22u}) {
    const WindField f = make_wind_field(gusty_wind(seed), 0.0, 1000.0, 600.0);
    WindFieldBuffer values;
    values.reset(f);
    const double period = f.samples * f.dt;
    const long total = static_cast<long>(std::floor(period * fs));
    std::vector<int> probes;
    for (int j = 0; j < f.points; j += 20) probes.push_back(j);
    ASSERT_GE(probes.size(), 10u);
    std::vector<double> pts(f.held);
    std::vector<std::vector<double>> series(probes.size(), std::vector<double>(total));
    for (long n = 0; n < total; ++n) {
      values.at_time(f, n / fs, pts.data());
      for (std::size_t p = 0; p < probes.size(); ++p) series[p][n] = pts[probes[p]];
    }
    for (const std::vector<double>& s : series)
      for (long b = 0; b + seg <= total; b += seg) {
        double mean = 0.0;
        for (int n = 0; n < seg; ++n) mean += s[b + n];
        mean /= seg;
        for (int n = 0; n < seg; ++n) x[n] = window[n] * (s[b + n] - mean);
        fft.fwd(X, x);
        for (int k = 0; k <= seg / 2; ++k) psd[k] += 2.0 * std::norm(X[k]) / (fs * w2);
        ++segments;
      }
  }
  ASSERT_GE(segments, 1500);
  // Tolerance from the estimator's scatter: a Hann periodogram ordinate of a Gaussian process is
  // S chi^2_2 / 2 (relative std 1); the mean over K segments has 1/sqrt(K); the mean over B = 5
  // adjacent bins, whose periodograms correlate by 4/9 (one bin apart) and 1/36 (two), has the
  // variance (1 + 2 (4/5) 4/9 + 2 (3/5) / 36) / (K B) = 1.74 / (K B): with K >= 1500 a relative
  // std of 1.5 %. Four of them, plus 1 % for the Hann window's smoothing of the f^-5/3 slope
  // over its +-2-bin main lobe (S'' / S df^2 at 1.5 Hz): 7 %. A field cut by linear interpolation
  // of samples 1 / (2 max_frequency) apart falls short by sinc^4(f / (2 f_max)): 14 % at 1.5 Hz,
  // 67 % at 4 Hz.
  const double rel_std = std::sqrt(1.74 / (segments * (2.0 * half_band + 1.0)));
  const double tolerance = 4.0 * rel_std + 0.01;
  for (double fc : centres) {
    const int kc = static_cast<int>(std::lround(fc / df));
    double measured = 0.0, expected = 0.0;
    for (int k = kc - half_band; k <= kc + half_band; ++k) {
      measured += psd[k] / segments;
      expected += von_karman_spectrum(k * df, U, sigma, L);
    }
    EXPECT_NEAR(measured / expected, 1.0, tolerance) << "band around " << fc << " Hz";
    std::printf("%.2f Hz: measured / von Karman %.4f (tolerance %.4f)\n", fc, measured / expected, tolerance);
  }
}

TEST(WindField, EndlessLinesFieldHasABoundedSizeWhateverTheDistance) {
  // A 3-D endless line in a gusty cross wind on a 200 km pass: the field over the whole pass
  // would be 40,000 points of 16,384 samples (2.6 GB of series, and 5 GB of coefficients while
  // made); the state holds its block's points and generates those ahead as the block moves on.
  const std::vector<std::string> ov = {"train.start=0", "train.end=200000", "numerics.preset=fast",
                                       "stagger.contact_wire=[0.3,-0.3]", "stagger.messenger=[0.0]",
                                       "wind.speed=20", "wind.turbulence.intensity=0.15", "wind.turbulence.seed=5"};
  const std::string endless = test_scenes::kReferenceEndless;
  const Scene scene = load_scene_file(endless, ov);
  Simulation sim(scene);
  const Model& m = sim.model();
  ASSERT_TRUE(m.lateral);
  const WindField& f = m.lateral->field;
  ASSERT_FALSE(f.empty());
  const WindFieldBuffer& held = sim.state().lateral.wind_field;
  // The points held: the block's and those around its ends (wind_field.cpp), against the pass's.
  EXPECT_LE(f.held, static_cast<int>(std::ceil(m.line_length / f.dx)) + 3);
  EXPECT_GT(f.points, 30 * f.held);
  const std::size_t bytes = held.bytes();
  EXPECT_GT(bytes, 0u);
  EXPECT_LE(bytes, f.buffer_bytes());
  // The model's memory estimate counts it (the initial state's and the running state's) on top of
  // the same line in a steady wind.
  Scene block = m.scene;
  Scene block_steady = block;
  block_steady.wind->turbulence.reset();
  EXPECT_GE(estimate_model_bytes(block) - estimate_model_bytes(block_steady), 2.0 * bytes);
  // Running on: the buffer keeps its size while the held points move along the line with the block.
  const int first = held.first();
  const double offset = sim.state().line_offset;
  while (sim.state().line_offset < offset + 600.0) ASSERT_EQ(sim.step(), StepStatus::kOk) << sim.status_message();
  EXPECT_EQ(sim.state().lateral.wind_field.bytes(), bytes);
  EXPECT_GE(sim.state().lateral.wind_field.first() - first, static_cast<int>(600.0 / f.dx) - 1);
  EXPECT_EQ(sim.state().lateral.wind_field.end() - sim.state().lateral.wind_field.first(), f.held);
}

TEST(WindField, ARingOfPointsIsTheFieldOfTheWholeStretch) {
  // The endless line's ring (a few points held) against every point held, from the same first
  // station: the same series to the bit at every point, however far the ring has run.
  const WindField all = make_wind_field(gusty_wind(9), 0.0, 800.0, 120.0);
  const WindField ring = make_wind_field(gusty_wind(9), 0.0, 800.0, 120.0, 40.0);
  ASSERT_EQ(all.samples, ring.samples);
  ASSERT_LT(ring.held, 15);
  WindFieldBuffer a, b;
  a.reset(all);
  b.reset(ring);
  std::vector<double> va(all.held), vb(ring.held);
  for (int step = ring.held - 1;; step += 7) {
    const int last = std::min(step, all.points - 1);
    b.extend_to(ring, last);
    const double t = 0.37 * last;
    a.at_time(all, t, va.data());
    b.at_time(ring, t, vb.data());
    for (int j = b.first(); j < b.end(); ++j) ASSERT_EQ(vb[j - b.first()], va[j]) << "point " << j << " at " << last;
    if (last == all.points - 1) break;
  }
  EXPECT_EQ(b.end(), all.points);
}
