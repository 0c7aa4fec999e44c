#include "catenary_sim/core/output/line_measures.hpp"

#include <algorithm>
#include <cmath>
#include <complex>

namespace catenary_sim {

std::vector<ContactLossEvent> contact_loss_events(const std::vector<double>& t, const std::vector<double>& x,
                                                  const std::vector<double>& force, double x0, double x1) {
  std::vector<ContactLossEvent> out;
  const std::size_t n = std::min({t.size(), x.size(), force.size()});
  bool open = false;
  ContactLossEvent ev;
  std::size_t last_in = 0;
  auto close = [&](double t_end, double x_end) {
    ev.duration = t_end - ev.start_time;
    ev.length = x_end - ev.station;
    out.push_back(ev);
    open = false;
  };
  for (std::size_t i = 0; i < n; ++i) {
    const bool in = x[i] >= x0 && x[i] <= x1;
    if (!in) {
      // Leaving the section cuts a running loss at this sample.
      if (open) close(t[i], x[i]);
      continue;
    }
    last_in = i;
    const bool lost = !(force[i] > 0.0);
    if (lost && !open) {
      ev = ContactLossEvent{};
      ev.start_time = t[i];
      ev.station = x[i];
      open = true;
    } else if (!lost && open) {
      close(t[i], x[i]);
    }
  }
  if (open) {
    // Still lost at the last sample: it stands for one sample period.
    const double period = last_in > 0 ? t[last_in] - t[last_in - 1] : 0.0;
    const double dx = last_in > 0 ? x[last_in] - x[last_in - 1] : 0.0;
    close(t[last_in] + period, x[last_in] + dx);
  }
  return out;
}

std::vector<double> TurningPoints::points() const {
  std::vector<double> p;
  p.reserve(points_.size() + 1);
  p = points_;
  if (started_) p.push_back(last_);
  return p;
}

std::vector<double> turning_points(const std::vector<double>& x) {
  TurningPoints tp;
  for (double v : x) tp.add(v);
  return tp.points();
}

std::vector<RainflowCycle> rainflow(const std::vector<double>& reversals) {
  std::vector<RainflowCycle> out;
  out.reserve(reversals.size());  // each cycle or half cycle takes at least one reversal off
  std::vector<double> stack;
  stack.reserve(64);
  auto cycle = [&](double a, double b, double count) {
    out.push_back(RainflowCycle{std::fabs(a - b), 0.5 * (a + b), count});
  };
  for (double r : reversals) {
    stack.push_back(r);  // step 1: read the next peak or valley
    while (stack.size() >= 3) {  // step 2: ranges X (latest) and Y (the one before)
      const std::size_t k = stack.size();
      const double X = std::fabs(stack[k - 1] - stack[k - 2]);
      const double Y = std::fabs(stack[k - 2] - stack[k - 3]);
      if (X < Y) break;  // step 3
      if (k == 3) {
        // Step 5: Y contains the starting point: half a cycle, the starting point moves on.
        cycle(stack[0], stack[1], 0.5);
        stack.erase(stack.begin());
      } else {
        // Step 4: a full cycle; both points of Y are discarded.
        cycle(stack[k - 3], stack[k - 2], 1.0);
        stack.erase(stack.begin() + static_cast<std::ptrdiff_t>(k - 3), stack.begin() + static_cast<std::ptrdiff_t>(k - 1));
      }
    }
  }
  // Step 6: every range not counted yet is half a cycle.
  for (std::size_t i = 0; i + 1 < stack.size(); ++i) cycle(stack[i], stack[i + 1], 0.5);
  return out;
}

std::vector<double> rainflow_histogram(const std::vector<RainflowCycle>& cycles, double max_range, int bins) {
  std::vector<double> h(static_cast<std::size_t>(std::max(bins, 0)), 0.0);
  if (bins <= 0 || !(max_range > 0.0)) return h;
  for (const RainflowCycle& c : cycles) {
    if (!(c.range <= max_range)) continue;
    const int b = std::min(bins - 1, static_cast<int>(std::floor(c.range / max_range * bins)));
    h[static_cast<std::size_t>(b)] += c.count;
  }
  return h;
}

namespace {

// In-place iterative radix-2 FFT; a.size() must be a power of two.
void fft(std::vector<std::complex<double>>& a) {
  const std::size_t n = a.size();
  for (std::size_t i = 1, j = 0; i < n; ++i) {
    std::size_t bit = n >> 1;
    for (; j & bit; bit >>= 1) j ^= bit;
    j ^= bit;
    if (i < j) std::swap(a[i], a[j]);
  }
  for (std::size_t len = 2; len <= n; len <<= 1) {
    const double ang = -2.0 * M_PI / static_cast<double>(len);
    const std::complex<double> wl(std::cos(ang), std::sin(ang));
    for (std::size_t i = 0; i < n; i += len) {
      std::complex<double> w(1.0, 0.0);
      for (std::size_t k = 0; k < len / 2; ++k) {
        const std::complex<double> u = a[i + k], v = a[i + k + len / 2] * w;
        a[i + k] = u + v;
        a[i + k + len / 2] = u - v;
        w *= wl;
      }
    }
  }
}

}  // namespace

Spectrum welch_psd(const std::vector<double>& x, double fs, std::size_t segment) {
  Spectrum s;
  const std::size_t n = x.size();
  if (n < 2 || !(fs > 0.0)) return s;
  const std::size_t seg = std::max<std::size_t>(2, std::min(segment, n));
  const std::size_t step = seg - seg / 2;
  std::size_t nfft = 1;
  while (nfft < seg) nfft <<= 1;
  std::vector<double> w(seg);
  double w2 = 0.0;
  for (std::size_t i = 0; i < seg; ++i) {
    w[i] = 0.5 - 0.5 * std::cos(2.0 * M_PI * static_cast<double>(i) / static_cast<double>(seg));  // periodic Hann
    w2 += w[i] * w[i];
  }
  const std::size_t bins = nfft / 2 + 1;
  s.psd.assign(bins, 0.0);
  std::vector<std::complex<double>> buf(nfft);
  std::size_t count = 0;
  for (std::size_t start = 0; start + seg <= n; start += step) {
    double mean = 0.0;
    for (std::size_t i = 0; i < seg; ++i) mean += x[start + i];
    mean /= static_cast<double>(seg);
    std::fill(buf.begin(), buf.end(), std::complex<double>(0.0, 0.0));
    for (std::size_t i = 0; i < seg; ++i) buf[i] = (x[start + i] - mean) * w[i];
    fft(buf);
    for (std::size_t k = 0; k < bins; ++k) s.psd[k] += std::norm(buf[k]);
    ++count;
  }
  const double scale = 1.0 / (fs * w2 * static_cast<double>(count));
  for (std::size_t k = 0; k < bins; ++k) {
    const bool edge = k == 0 || (nfft % 2 == 0 && k == bins - 1);
    s.psd[k] *= scale * (edge ? 1.0 : 2.0);
  }
  s.frequency.resize(bins);
  for (std::size_t k = 0; k < bins; ++k) s.frequency[k] = fs * static_cast<double>(k) / static_cast<double>(nfft);
  s.resolution = fs / static_cast<double>(seg);
  s.segment = seg;
  s.segments = count;
  return s;
}

std::vector<SpectralPeak> spectral_peaks(const Spectrum& s, double f_lo, double f_hi, std::size_t count) {
  std::vector<SpectralPeak> cand;
  const std::size_t n = s.psd.size();
  if (n < 3) return cand;
  const double df = s.frequency[1] - s.frequency[0];
  for (std::size_t k = 1; k + 1 < n; ++k) {
    const double f = s.frequency[k];
    if (f < f_lo || f > f_hi) continue;
    if (!(s.psd[k] > s.psd[k - 1] && s.psd[k] >= s.psd[k + 1])) continue;
    SpectralPeak p;
    p.frequency = f;
    p.psd = s.psd[k];
    // The power of a sine is spread over the window's main lobe (+-2 resolutions) and a little
    // beyond: sum +-3 resolutions.
    const double half = 3.0 * s.resolution;
    double power = 0.0;
    const std::size_t h = static_cast<std::size_t>(std::floor(half / df + 1e-9));
    for (std::size_t j = k > h ? k - h : 0; j < n && j <= k + h; ++j) power += s.psd[j] * df;
    p.amplitude = std::sqrt(2.0 * power);
    cand.push_back(p);
  }
  std::sort(cand.begin(), cand.end(), [](const SpectralPeak& a, const SpectralPeak& b) { return a.psd > b.psd; });
  std::vector<SpectralPeak> out;
  for (const SpectralPeak& p : cand) {
    if (out.size() >= count) break;
    bool near = false;
    for (const SpectralPeak& q : out) near |= std::fabs(p.frequency - q.frequency) < 4.0 * s.resolution;
    if (!near) out.push_back(p);
  }
  return out;
}

}  // namespace catenary_sim
