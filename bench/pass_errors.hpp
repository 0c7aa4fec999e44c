// A pass of the reference scene measured for the accuracy benchmarks (bench_speed_accuracy,
// bench_reference_rung): its size, step, wall time and statistics, and the errors of its statistics
// against a finer solution's.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ostream>
#include <string>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "../test/support/scenes.hpp"

namespace bench {

// The scene both benches measure unless given another.
inline const std::string& kReferenceScene = test_scenes::kReference;

struct PassResult {
  int dofs = 0;
  double dt = 0.0, wall = 0.0, rtf = 0.0;  // s, s (median of the repeats), real-time factor
  catenary_sim::PantographStatistics s20, s200;  // the first pantograph's, 0-20 Hz and 0-200 Hz
};

// The scene at `path` with `overrides` at `kmh`, run `reps` times (the wall time is the median).
inline PassResult run_pass(const std::string& path, std::vector<std::string> overrides, double kmh, int reps = 1) {
  using namespace catenary_sim;
  overrides.push_back("train.speed_kmh=" + std::to_string(kmh));
  const Scene scene = load_scene_file(path, overrides);
  PassResult r;
  std::vector<double> walls;
  double simulated = 0.0;
  for (int i = 0; i < reps; ++i) {
    Simulation sim(scene);
    const Model& m = sim.model();
    PassRecorder rec(m);
    rec.record(m, sim.state());
    const auto t0 = std::chrono::steady_clock::now();
    while (sim.step() == StepStatus::kOk) rec.record(m, sim.state());
    walls.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    r.dofs = m.n_dof;
    r.dt = m.dt;
    r.s20 = rec.statistics(m, 20.0)[0];
    r.s200 = rec.statistics(m, 200.0)[0];
    simulated = sim.state().time;
  }
  std::sort(walls.begin(), walls.end());
  r.wall = walls[walls.size() / 2];
  r.rtf = simulated / r.wall;
  return r;
}

// Percent error of `a` against `ref`.
inline double rel(double a, double ref) { return 100.0 * std::fabs(a - ref) / std::fabs(ref); }

// The errors (%) of a pass's statistics against a finer one's: 0-20 Hz mean, std, max and min (the
// min relative to the finer mean, since the min can be near zero), and the 0-200 Hz max.
struct StatErrors {
  double mean = 0.0, std_dev = 0.0, max = 0.0, min = 0.0, max200 = 0.0;
};

inline StatErrors stat_errors(const PassResult& r, const PassResult& ref) {
  StatErrors e;
  e.mean = rel(r.s20.filtered.mean, ref.s20.filtered.mean);
  e.std_dev = rel(r.s20.filtered.std_dev, ref.s20.filtered.std_dev);
  e.max = rel(r.s20.filtered.max, ref.s20.filtered.max);
  e.min = 100.0 * std::fabs(r.s20.filtered.min - ref.s20.filtered.min) / ref.s20.filtered.mean;
  e.max200 = rel(r.s200.filtered.max, ref.s200.filtered.max);
  return e;
}

// The CSV both benches write: a header, then a row a variant.
inline const char* const kCsvHeader =
    "speed_kmh,variant,dofs,dt_s,wall_s,rtf,err_mean_pct,err_std_pct,err_max_pct,err_min_pct,err_max200_pct\n";

inline void csv_row(std::ostream& csv, double kmh, const std::string& variant, int dofs, double dt, double wall, double rtf,
                    const StatErrors& e) {
  csv << kmh << "," << variant << "," << dofs << "," << dt << "," << wall << "," << rtf << "," << e.mean << ","
      << e.std_dev << "," << e.max << "," << e.min << "," << e.max200 << "\n";
}

}  // namespace bench
