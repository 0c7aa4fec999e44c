// Times the reference pass (config/reference_55m.yaml, 300 km/h, h = 0.25 m, explicit) and prints
// DOFs, dt, steps, wall time and real-time factor; the lumped-rotary-inertia (HRZ) variant runs
// in the same process so the two can be compared as a ratio on the same machine and load. The
// default variant also runs with a PassRecorder recording every step (as simulate_pass does),
// with and without the per-dropper recording, so the recording's cost is a ratio too.
//   bench_reference_pass [repetitions=5] [scene=config/reference_55m.yaml]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "../test/support/scenes.hpp"
#include "bench_cli.hpp"
#include "guarded_main.hpp"

using namespace catenary_sim;

static int bench_main(int argc, char** argv) {
  CLI::App app{"Times the reference pass (300 km/h, h = 0.25 m, explicit) beside its lumped-rotary-inertia variant "
               "and with the recorders, in one process.",
               "bench_reference_pass"};
  int reps = 5;
  std::string path = test_scenes::kReference;
  bench::add_repetitions(app, reps);
  bench::add_scene(app, path);
  CLI11_PARSE(app, argc, argv);
  std::printf("%-34s %6s %9s %7s %10s %10s %8s\n", "variant", "DOFs", "dt_ms", "steps", "wall_med_s", "wall_min_s", "RTF_med");
  struct Variant {
    std::string label;
    std::vector<std::string> overrides;
    int recorder;  // 0 none, 1 PassRecorder without droppers, 2 PassRecorder with droppers
  };
  const std::vector<std::string> base{"train.speed_kmh=300", "numerics.element_length=0.25"};
  const std::vector<Variant> variants{
      {"condensed rotations (default)", base, 0},
      {"  + PassRecorder, no droppers", base, 1},
      {"  + PassRecorder (simulate_pass)", base, 2},
      {"lumped rotary inertia (HRZ)", {"train.speed_kmh=300", "numerics.element_length=0.25", "numerics.rotary_inertia=lumped"}, 0}};
  struct Result {
    std::vector<double> walls;
    long steps = 0;
    double sim_time = 0.0, dt = 0.0;
    int dofs = 0;
  };
  std::vector<Scene> scenes;
  for (const Variant& v : variants) scenes.push_back(load_scene_file(path, v.overrides));
  std::vector<Result> results(variants.size());
  // Repetitions interleaved over the variants, so that a change of the machine's load (it is
  // shared) falls on all of them alike and the ratios stay meaningful.
  for (int r = 0; r < reps; ++r)
    for (std::size_t i = 0; i < variants.size(); ++i) {
      const Scene& scene = scenes[i];
      Simulation sim(scene);  // model building and statics are not timed: only the pass
      const Model& m = sim.model();
      std::unique_ptr<PassRecorder> rec;
      if (variants[i].recorder) rec = std::make_unique<PassRecorder>(m, scene.output.sample_rate, variants[i].recorder == 2);
      const auto t0 = std::chrono::steady_clock::now();
      if (rec) {
        rec->record(m, sim.state());
        while (sim.step() == StepStatus::kOk) rec->record(m, sim.state());
      } else {
        while (sim.step() == StepStatus::kOk) {
        }
      }
      Result& res = results[i];
      res.walls.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      res.steps = sim.state().steps;
      res.sim_time = sim.state().time;
      res.dt = m.dt;
      res.dofs = m.n_dof;
    }
  std::vector<double> medians;
  for (std::size_t i = 0; i < variants.size(); ++i) {
    Result& res = results[i];
    std::sort(res.walls.begin(), res.walls.end());
    const double med = res.walls[res.walls.size() / 2];
    medians.push_back(med);
    std::printf("%-34s %6d %9.4f %7ld %10.4f %10.4f %8.1f\n", variants[i].label.c_str(), res.dofs, res.dt * 1e3, res.steps,
                med, res.walls.front(), res.sim_time / med);
  }
  std::printf("recorder cost (median wall / bare): no droppers %.3f, full %.3f; full / no droppers %.3f\n",
              medians[1] / medians[0], medians[2] / medians[0], medians[2] / medians[1]);
  return 0;
}

int main(int argc, char** argv) { return bench::guarded_main("bench_reference_pass", argc, argv, bench_main); }
