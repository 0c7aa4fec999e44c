// Soak of an endless pass as a live node runs it for hours: the recorders (PassRecorder,
// LateralRecorder) fed every step, and every REPORT simulated seconds a line with the bytes they
// hold, the process's resident set, the wall time of statistics() and the real-time factor. On a
// recorder in bounded memory the bytes and the statistics' time are flat after the warm-up.
//   bench_endless_soak [--hours H] [--report S] [--scene FILE] [field=value ...]
// Defaults: 2 h simulated of config/reference_55m_endless.yaml on the fast rung at 300 km/h,
// every 600 s. The time series at 0.001 Hz (a node that asks for few rows): the rows add nothing.
// Against another checkout's core (no memory_bytes() there; the RSS column still tells):
//   g++ -O3 -DNDEBUG -std=c++17 -DBENCH_SOAK_NO_ACCESSOR -I/tmp/base/include -I/usr/include/eigen3
//       bench/bench_endless_soak.cpp /tmp/base/.ws/devel/lib/libcatenary_sim_core.a -lyaml-cpp
//       -o /tmp/bench_endless_soak_base
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "catenary_sim/core/output/lateral_statistics.hpp"
#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "../test/support/scenes.hpp"
#include "bench_cli.hpp"
#include "guarded_main.hpp"

using namespace catenary_sim;

namespace {

double rss_mb() {
  long pages = 0, resident = 0;
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return -1.0;
  const int n = std::fscanf(f, "%ld %ld", &pages, &resident);
  std::fclose(f);
  return n == 2 ? resident * static_cast<double>(::sysconf(_SC_PAGESIZE)) / 1e6 : -1.0;
}

}  // namespace

static int bench_main(int argc, char** argv) {
  CLI::App app{"Soak of an endless pass as a live node runs it for hours: the recorders' bytes, the resident set and "
               "the statistics' wall time every REPORT simulated seconds.",
               "bench_endless_soak"};
  double hours = 2.0, report = 600.0;
  std::string scene = test_scenes::kReferenceEndless;
  std::vector<std::string> given;
  // A year of simulated time is more than any soak.
  app.add_option("--hours", hours, "simulated time, h")
      ->check(bench::kFinite & bench::positive_up_to(8760.0))
      ->capture_default_str();
  app.add_option("--report", report, "simulated seconds between the report's lines")
      ->check(bench::kFinite & bench::positive_up_to(8760.0 * 3600.0))
      ->capture_default_str();
  app.add_option("--scene", scene, "scene YAML of an endless line")->check(CLI::ExistingFile)->capture_default_str();
  bench::add_overrides(app, given, "overrides of the scene's fields, after the fast rung at 300 km/h");
  CLI11_PARSE(app, argc, argv);
  std::vector<std::string> overrides = {"numerics.preset=fast", "output.sample_rate=0.001", "train.speed_kmh=300"};
  overrides.insert(overrides.end(), given.begin(), given.end());
  // The pass long enough for the soak (train.end at the scene's speed, with a span to spare).
  {
    const Scene probe = load_scene_file(scene, overrides);
    overrides.push_back("train.end=" + std::to_string(probe.train_speed * (hours * 3600.0 + 10.0) + 1000.0));
  }
  Simulation sim(load_scene_file(scene, overrides));
  const Model& m = sim.model();
  if (!m.endless) {
    std::fprintf(stderr, "bench_endless_soak: %s is not an endless line\n", scene.c_str());
    return 2;
  }
  PassRecorder rec(m, m.scene.output.sample_rate);
  LateralRecorder lat(m, m.scene.output.sample_rate);
  rec.record(m, sim.state());
  lat.record(m, sim.state());
  std::printf("# %s, %d DOFs, dt %.4g ms, %.0f km/h, %s\n", m.scene.name.c_str(), m.n_dof, m.dt * 1e3,
              m.scene.train_speed * 3.6, m.lateral ? "3-D" : "2-D");
  std::printf("%12s %10s %14s %14s %10s %14s %8s\n", "simulated_s", "wall_s", "recorder_B", "lateral_B", "rss_MB",
              "statistics_ms", "rtf");
  std::fflush(stdout);
  double section_start = 0.0, section_end = 0.0;
  analysis_section(m, &section_start, &section_end);
  bool analysed = false;
  const auto t0 = std::chrono::steady_clock::now();
  double next = report;
  while (sim.state().time < hours * 3600.0) {
    if (sim.step() != StepStatus::kOk) {
      std::fprintf(stderr, "bench_endless_soak: %s\n", sim.status_message().c_str());
      return 1;
    }
    rec.record(m, sim.state());
    lat.record(m, sim.state());
    if (sim.state().time < next) continue;
    next += report;
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const auto s0 = std::chrono::steady_clock::now();
    const std::vector<PantographStatistics> st = rec.statistics(m);
    const double stat_ms = std::chrono::duration<double>(std::chrono::steady_clock::now() - s0).count() * 1e3;
#ifdef BENCH_SOAK_NO_ACCESSOR
    const double rb = -1.0, lb = -1.0;
#else
    const double rb = static_cast<double>(rec.memory_bytes()), lb = static_cast<double>(lat.memory_bytes());
#endif
    std::printf("%12.0f %10.1f %14.0f %14.0f %10.1f %14.1f %8.2f\n", sim.state().time, wall, rb, lb, rss_mb(), stat_ms,
                sim.state().time / wall);
    std::fflush(stdout);
    if (st.empty() || !(st[0].filtered.mean == st[0].filtered.mean)) {
      // The statistics start with the analysis section (the pass's spans but two at each end) and
      // need a span of it for the filter: an early report has none yet, a later one must.
      const double rear = sim.state().front + sim.state().line_offset + m.rear_collector_offset;
      if (rear < section_start + m.endless_span) {
        std::printf("# no statistics yet: the analysis section starts at %.0f m, the rearmost collector is at %.0f m\n",
                    section_start, rear);
        continue;
      }
      std::fprintf(stderr,
                   "bench_endless_soak: no statistics at t = %.1f s, with the rearmost collector at %.0f m, a span past "
                   "the analysis section's start at %.0f m\n",
                   sim.state().time, rear, section_start);
      return 1;
    }
    analysed = true;
  }
  if (!analysed)
    std::printf("# the soak ended before the analysis section's first span (from %.0f m): no statistics were timed; "
                "raise --hours\n",
                section_start);
  return 0;
}

int main(int argc, char** argv) { return bench::guarded_main("bench_endless_soak", argc, argv, bench_main); }
