// Recording an endless pass in bounded memory (pass_recorder.hpp, "An endless line's pass"): the
// recorders of an endless line stepped for 10 simulated minutes hold a constant amount after the
// warm-up, and their running statistics are those of the whole record.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "catenary_sim/core/output/lateral_statistics.hpp"
#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "catenary_sim/core/model/wind_field.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;

namespace {

const std::string kEndless = test_scenes::kConfigDir + "reference_55m_endless.yaml";
const std::string kFinite = test_scenes::kConfigDir + "reference_55m.yaml";

// Resident set size of this process (bytes), from /proc/self/statm.
double rss_bytes() {
  long pages = 0, resident = 0;
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return std::nan("");
  const int n = std::fscanf(f, "%ld %ld", &pages, &resident);
  std::fclose(f);
  return n == 2 ? static_cast<double>(resident) * static_cast<double>(::sysconf(_SC_PAGESIZE)) : std::nan("");
}

struct Soak {
  std::vector<double> recorder_bytes, lateral_bytes, rss;  // at every minute
  std::vector<PantographStatistics> stats;
  double simulated = 0.0;
  double whole_pass_field_bytes = 0.0;  // a turbulent field over every station the pass covers
};

// An endless pass of `minutes` simulated minutes on the fast rung (1 m elements: the recording's
// memory does not depend on the mesh), the time series at 0.001 Hz (what an idle node asks for),
// recorders sampled every simulated minute.
Soak soak(std::vector<std::string> overrides, int minutes) {
  overrides.insert(overrides.end(), {"numerics.preset=fast", "output.sample_rate=0.001", "train.speed_kmh=200",
                                     "train.end=" + std::to_string(200 / 3.6 * 60.0 * (minutes + 1) + 1000.0)});
  Simulation sim(load_scene_file(kEndless, overrides));
  const Model& m = sim.model();
  PassRecorder rec(m, m.scene.output.sample_rate);
  LateralRecorder lat(m, m.scene.output.sample_rate);
  rec.record(m, sim.state());
  lat.record(m, sim.state());
  Soak out;
  double next = 60.0;
  while (sim.state().time < 60.0 * minutes) {
    EXPECT_EQ(sim.step(), StepStatus::kOk) << sim.status_message();
    if (sim.state().status != StepStatus::kOk) break;
    rec.record(m, sim.state());
    lat.record(m, sim.state());
    if (sim.state().time >= next) {
      next += 60.0;
      out.recorder_bytes.push_back(static_cast<double>(rec.memory_bytes()));
      out.lateral_bytes.push_back(static_cast<double>(lat.memory_bytes()));
      out.rss.push_back(rss_bytes());
    }
  }
  out.stats = rec.statistics(m);
  out.simulated = sim.state().time;
  if (m.scene.wind && m.scene.wind->turbulence)
    out.whole_pass_field_bytes = wind_field_bytes_estimate(*m.scene.wind, 200 / 3.6 * 60.0 * minutes);
  return out;
}

// The bound after the warm-up (the spectrum's window of PassRecorder::kSpectrumWindow = 2 minutes
// in the section fills first; the filter's blocks within a second): what the recorder holds at 3
// minutes, plus what the lists that fill up to PassRecorder::kMaxListed entries may add (steady
// arms passed, loss events): 256 bytes an entry is a map node or a doubled vector's share several
// times over, 256 kB in all. A recorder that keeps a step's data (8 bytes a channel and step,
// 27,000 steps a simulated minute on this rung) grows by more than that every minute.
void expect_flat(const std::vector<double>& bytes, const char* what) {
  ASSERT_GE(bytes.size(), 10u) << what;
  const double bound = bytes[2] + 256.0 * PassRecorder::kMaxListed;
  for (std::size_t k = 3; k < bytes.size(); ++k)
    EXPECT_LE(bytes[k], bound) << what << " at minute " << k + 1 << ": " << bytes[k] << " bytes, " << bytes[2]
                               << " at minute 3";
}

}  // namespace

TEST(BoundedRecording, EndlessPassHoldsConstantMemory2D) {
  const Soak s = soak({}, 10);
  EXPECT_GE(s.simulated, 600.0);
  expect_flat(s.recorder_bytes, "PassRecorder");
  // The process as a whole (no wind field on this line): flat too. A per-step record of this pass
  // (time, position, force, a wire's force, three head channels: 7 doubles a step at about 27,000
  // steps a minute) would add 1.5 MB a minute, 10 MB over minutes 3..10; 4 MB is the allocator's
  // slack and the statistics' call.
  EXPECT_LT(s.rss.back() - s.rss[2], 4e6) << "RSS " << s.rss[2] << " -> " << s.rss.back();
  // The running statistics are what they are over a whole record: a pass with contact all along.
  ASSERT_EQ(s.stats.size(), 1u);
  EXPECT_GT(s.stats[0].samples, 0u);
  EXPECT_TRUE(std::isfinite(s.stats[0].filtered.mean));
  EXPECT_TRUE(s.stats[0].measured.available);
}

TEST(BoundedRecording, EndlessPassHoldsConstantMemory3D) {
  // Staggered +-0.3 m in a turbulent 20 m/s cross wind (config/reference_55m_3d.yaml's field): the
  // recorders, the lateral plane with its gust lead and the wind field generated as the block
  // moves must all hold a constant amount.
  const Soak s = soak({"stagger.contact_wire=[0.3, -0.3]", "stagger.messenger=[0.0]", "wind.speed=20",
                       "wind.turbulence.intensity=0.15", "wind.turbulence.seed=1"},
                      10);
  EXPECT_GE(s.simulated, 600.0);
  expect_flat(s.recorder_bytes, "PassRecorder");
  expect_flat(s.lateral_bytes, "LateralRecorder");
  // The process as a whole: flat after the warm-up (the ring's regeneration works in buffers made
  // once; 4 MB is the allocator's slack and the statistics' call, as on the 2-D line), and far
  // below what the field of every station the pass covers would take (34 km of line: a field made
  // for the whole pass would hold that from the start, so flatness alone would not show it). The
  // ring holds the block's and the gust lead's points, a few km (about 0.25 of the whole pass's
  // 34 km here, with the model: RSS 122 of 438 MB); a whole-pass field even at half this field's
  // samples per point holds 0.5 of it plus the model, so 0.4 tells the two apart.
  ASSERT_GT(s.whole_pass_field_bytes, 0.0);
  EXPECT_LT(s.rss.back(), 0.4 * s.whole_pass_field_bytes) << "RSS " << s.rss.back() << " B, field of the whole pass "
                                                            << s.whole_pass_field_bytes << " B";
  EXPECT_LT(s.rss.back() - s.rss[2], 4e6) << "RSS " << s.rss[2] << " -> " << s.rss.back();
}

TEST(BoundedRecording, RunningStatisticsAreTheWholeRecords) {
  // The endless pass's running statistics against the whole-record reduction of the same steps: a
  // finite recorder fed the same states is not possible (the recorder takes its mode from the
  // model), so the reference is computed here from the steps themselves, with the library's own
  // whole-record functions (lowpass_zero_phase, force_statistics, contact_loss_events).
  std::vector<std::string> ov = {"numerics.preset=fast", "train.end=2200"};
  Simulation sim(load_scene_file(kEndless, ov));
  const Model& m = sim.model();
  PassRecorder rec(m, 0.0);
  rec.record(m, sim.state());
  std::vector<double> t, x, f;
  auto keep = [&](const State& s) {
    t.push_back(s.time);
    x.push_back((s.front - m.pantographs[0].position) + s.line_offset);  // as the recorder adds it
    f.push_back(total_contact_force(m, s, 0));
  };
  keep(sim.state());
  while (sim.step() == StepStatus::kOk) {
    rec.record(m, sim.state());
    keep(sim.state());
  }
  ASSERT_TRUE(rec.running());
  double x0 = 0.0, x1 = 0.0;
  analysis_section(m, &x0, &x1);
  const std::vector<double> filtered = lowpass_zero_phase(f, 1.0 / m.dt, m.scene.output.filter_cutoff);
  std::vector<double> fin, rin;
  for (std::size_t i = 0; i < f.size(); ++i)
    if (x[i] >= x0 && x[i] <= x1) {
      fin.push_back(filtered[i]);
      rin.push_back(f[i]);
    }
  const ForceStatistics ref = force_statistics(fin), raw = force_statistics(rin);
  const PantographStatistics st = rec.statistics(m)[0];
  EXPECT_EQ(st.samples, rin.size());
  // The blocks' overlap leaves the filter's transient at 2e-17 of the force (pass_recorder.hpp), and
  // the running mean and variance (Welford) round differently from the two-pass sums: 1e-9
  // relative is a million times that rounding and far below any physical difference (a block
  // filtered without its overlap is off by percents at the block edges).
  const double tol = 1e-9 * ref.mean;
  EXPECT_NEAR(st.filtered.mean, ref.mean, tol);
  EXPECT_NEAR(st.filtered.std_dev, ref.std_dev, tol);
  EXPECT_NEAR(st.filtered.max, ref.max, tol);
  EXPECT_NEAR(st.filtered.min, ref.min, tol);
  EXPECT_NEAR(st.unfiltered.mean, raw.mean, tol);
  EXPECT_NEAR(st.unfiltered.std_dev, raw.std_dev, tol);
  EXPECT_EQ(st.unfiltered.max, raw.max);
  EXPECT_EQ(st.unfiltered.min, raw.min);
  const std::vector<ContactLossEvent> events = contact_loss_events(t, x, f, x0, x1);
  EXPECT_EQ(st.loss_events_total, events.size());
  // The processed rows (every step here) carry the same filtered force at every step.
  const std::deque<PassRecorder::Row> rows = rec.processed_rows(m);
  ASSERT_EQ(rows.size(), f.size());
  double worst = 0.0;
  for (std::size_t i = 0; i < rows.size(); ++i) worst = std::max(worst, std::fabs(rows[i].values[1] - filtered[i]));
  EXPECT_LT(worst, tol);
}

TEST(BoundedRecording, MovingForceMeasuredColumnIsTheAppliedForce) {
  // force_processed.csv's measured force of a moving force (no head, no sensor): the force it
  // applies, here the static uplift on one contact wire wherever it is under the wire; never NaN.
  for (const std::string& scene : {kFinite, kEndless}) {
    std::vector<std::string> ov = {"pantographs.0.type=moving_force", "pantographs.0.masses=null",
                                   "pantographs.0.stiffness=null", "pantographs.0.damping=null", "numerics.preset=fast"};
    if (scene == kEndless) ov.push_back("train.end=1200");
    Simulation sim(load_scene_file(scene, ov));
    const Model& m = sim.model();
    ASSERT_TRUE(m.pantographs[0].moving_force);
    PassRecorder rec(m, 100.0);
    rec.record(m, sim.state());
    while (sim.step() == StepStatus::kOk) rec.record(m, sim.state());
    const std::deque<PassRecorder::Row> rows = rec.processed_rows(m);
    ASSERT_GT(rows.size(), 10u);
    const double uplift = m.scene.pantographs[0].static_uplift;
    std::size_t under = 0;
    for (const PassRecorder::Row& r : rows) {
      ASSERT_TRUE(std::isfinite(r.values[2])) << scene << " t = " << r.time;
      // On the wire the force is the uplift exactly (the rule of contact_forces: a moving force
      // pushes the lowest wire with what it is given); off the line's ends 0.
      EXPECT_TRUE(r.values[2] == uplift || r.values[2] == 0.0) << r.values[2];
      under += r.values[2] == uplift;
    }
    EXPECT_GT(under, rows.size() / 2) << scene;
  }
}
