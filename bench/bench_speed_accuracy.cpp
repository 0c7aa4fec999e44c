// The fidelity ladder measured: the reference scene at 250 and 300 km/h for every preset, with the
// moving window off and on (and the implicit integrator as a knob), with DOFs, dt, wall time, real-time factor, and the error
// against `reference` in the 0-20 Hz statistics (mean, std, max, min) and in the 0-200 Hz max.
//   bench_speed_accuracy [scene=config/reference_55m.yaml] [csv=speed_accuracy.csv]
// Errors are relative to the reference value (for the min: relative to the reference mean,
// since the min can be near zero). Wall time is the median of 3 runs for the cheap variants.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/statistics.hpp"

#ifndef CATENARY_SIM_SOURCE_DIR
#define CATENARY_SIM_SOURCE_DIR "."
#endif

using namespace catenary_sim;

namespace {

struct Result {
  std::string label;
  int dofs = 0;
  double dt = 0.0, wall = 0.0, rtf = 0.0;
  PantographStatistics s20, s200;
};

Result run(const std::string& path, const std::string& label, std::vector<std::string> overrides, double kmh, int reps) {
  overrides.push_back("train.speed_kmh=" + std::to_string(kmh));
  const Scene scene = load_scene_file(path, overrides);
  Result r;
  r.label = label;
  std::vector<double> walls;
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
    r.rtf = sim.state().time;
  }
  std::sort(walls.begin(), walls.end());
  r.wall = walls[walls.size() / 2];
  r.rtf /= r.wall;
  return r;
}

double rel(double a, double ref) { return 100.0 * std::fabs(a - ref) / std::fabs(ref); }

}  // namespace

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : CATENARY_SIM_SOURCE_DIR "/config/reference_55m.yaml";
  const std::string csv_path = argc > 2 ? argv[2] : "speed_accuracy.csv";
  std::ofstream csv(csv_path);
  csv << "speed_kmh,variant,dofs,dt_s,wall_s,rtf,err_mean_pct,err_std_pct,err_max_pct,err_min_pct,err_max200_pct\n";
  for (double kmh : {250.0, 300.0}) {
    const Result ref = run(path, "reference", {"numerics.preset=reference"}, kmh, 1);
    const std::vector<std::pair<std::string, std::vector<std::string>>> variants = {
        {"fast", {"numerics.preset=fast"}},
        {"fast + window", {"numerics.preset=fast", "numerics.window=auto"}},
        {"balanced", {"numerics.preset=balanced"}},
        {"balanced + window", {"numerics.preset=balanced", "numerics.window=auto"}},
        {"accurate", {"numerics.preset=accurate"}},
        {"accurate + window", {"numerics.preset=accurate", "numerics.window=auto"}},
        {"implicit h=0.25 dt=1ms", {"numerics.integrator=implicit", "numerics.dt=0.001"}},
        {"implicit h=0.125 dt=1ms", {"numerics.integrator=implicit", "numerics.element_length=0.125", "numerics.dt=0.001"}},
    };
    std::printf("\n%.0f km/h (reference: %d DOFs, dt %.4f ms, %.2f s wall, %.1fx real time; std %.2f N, max %.2f N, 200 Hz max %.2f N)\n",
                kmh, ref.dofs, ref.dt * 1e3, ref.wall, ref.rtf, ref.s20.filtered.std_dev, ref.s20.filtered.max,
                ref.s200.filtered.max);
    std::printf("%-26s %6s %8s %8s %8s | %7s %7s %7s %7s | %8s\n", "variant", "DOFs", "dt_ms", "wall_s", "RTF", "mean%",
                "std%", "max%", "min%", "max200%");
    for (const auto& [label, ov] : variants) {
      const Result r = run(path, label, ov, kmh, 3);
      const double em = rel(r.s20.filtered.mean, ref.s20.filtered.mean);
      const double es = rel(r.s20.filtered.std_dev, ref.s20.filtered.std_dev);
      const double ex = rel(r.s20.filtered.max, ref.s20.filtered.max);
      const double en = 100.0 * std::fabs(r.s20.filtered.min - ref.s20.filtered.min) / ref.s20.filtered.mean;
      const double e200 = rel(r.s200.filtered.max, ref.s200.filtered.max);
      std::printf("%-26s %6d %8.4f %8.4f %8.1f | %7.2f %7.2f %7.2f %7.2f | %8.2f\n", label.c_str(), r.dofs, r.dt * 1e3,
                  r.wall, r.rtf, em, es, ex, en, e200);
      csv << kmh << "," << label << "," << r.dofs << "," << r.dt << "," << r.wall << "," << r.rtf << "," << em << "," << es
          << "," << ex << "," << en << "," << e200 << "\n";
    }
  }
  std::printf("\nwrote %s\n", csv_path.c_str());
  return 0;
}
