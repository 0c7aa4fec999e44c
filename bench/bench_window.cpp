// The moving window on a long line: the reference catenary on 100 spans (5.5 km) at 300 km/h,
// balanced preset, full line against numerics.window=auto, and the window's cost per simulated
// second against the 10-span line's (it must not grow with the line); then the endless line
// (config/reference_55m_endless.yaml) run over the same 100 spans and over ten times as many.
//   bench_window [spans=100]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "../test/support/scenes.hpp"
#include "bench_cli.hpp"
#include "guarded_main.hpp"

using namespace catenary_sim;

namespace {

struct Run {
  double wall = 0.0, sim_time = 0.0;
  int dofs = 0;
  PantographStatistics st;
};

Run run(std::vector<std::string> ov, const std::string& scene = test_scenes::kReference) {
  Simulation sim(load_scene_file(scene, ov));
  const Model& m = sim.model();
  PassRecorder rec(m);
  rec.record(m, sim.state());
  const auto t0 = std::chrono::steady_clock::now();
  while (sim.step() == StepStatus::kOk) rec.record(m, sim.state());
  Run r;
  r.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.sim_time = sim.state().time;
  r.dofs = m.n_dof;
  r.st = rec.statistics(m)[0];
  return r;
}

}  // namespace

static int bench_main(int argc, char** argv) {
  CLI::App app{"The moving window on a long line: the full line against numerics.window=auto, then the endless "
               "line over as many spans and ten times as many.",
               "bench_window"};
  int spans = 100;
  // At least 9: the statistics are over spans 4 to spans - 4. The endless line runs ten times as far.
  app.add_option("spans", spans, "spans of the long line")->check(CLI::Range(9, 1000))->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  const std::string n = "line.span_count=" + std::to_string(spans);
  const std::string section = "output.analysis_spans=[4," + std::to_string(spans - 4) + "]";
  const Run full = run({n, "numerics.preset=balanced", section});
  const Run win = run({n, "numerics.preset=balanced", section, "numerics.window=auto"});
  const Run short_win = run({"line.span_count=10", "numerics.preset=balanced", "numerics.window=auto"});
  auto row = [](const char* label, const Run& r) {
    std::printf("%-30s %6d %9.2f %8.3f %8.1f %9.3f | %7.2f %6.2f %7.2f %6.2f\n", label, r.dofs, r.sim_time, r.wall,
                r.sim_time / r.wall, 1e3 * r.wall / r.sim_time, r.st.filtered.mean, r.st.filtered.std_dev, r.st.filtered.max,
                r.st.filtered.min);
  };
  std::printf("%-30s %6s %9s %8s %8s %9s | %7s %6s %7s %6s\n", "run", "DOFs", "sim_s", "wall_s", "RTF", "ms/sim_s", "mean",
              "std", "max", "min");
  row(("full line, " + std::to_string(spans) + " spans").c_str(), full);
  row(("window auto, " + std::to_string(spans) + " spans").c_str(), win);
  row("window auto, 10 spans", short_win);
  std::printf("\nwindow cheaper by %.1fx; statistics change: mean %.2f %%, std %.2f %%, max %.2f %%, min %.2f %% of the mean\n",
              full.wall / win.wall, 100 * std::fabs(win.st.filtered.mean / full.st.filtered.mean - 1),
              100 * std::fabs(win.st.filtered.std_dev / full.st.filtered.std_dev - 1),
              100 * std::fabs(win.st.filtered.max / full.st.filtered.max - 1),
              100 * std::fabs(win.st.filtered.min - full.st.filtered.min) / full.st.filtered.mean);
  std::printf("cost per simulated second with the window: %.3f ms (%d spans) against %.3f ms (10 spans)\n",
              1e3 * win.wall / win.sim_time, spans, 1e3 * short_win.wall / short_win.sim_time);

  // The endless line over the same pass (front from 0 to the line's end) and ten times longer;
  // statistics over the same spans as above.
  const std::string& endless_scene = test_scenes::kReferenceEndless;
  const double length = 55.0 * spans;
  const Run endless = run({"numerics.preset=balanced", "train.end=" + std::to_string(length), section}, endless_scene);
  const Run endless_long = run({"numerics.preset=balanced", "train.end=" + std::to_string(10 * length), section}, endless_scene);
  std::printf("\n");
  row(("endless, " + std::to_string(spans) + " spans run").c_str(), endless);
  row(("endless, " + std::to_string(10 * spans) + " spans run").c_str(), endless_long);
  std::printf("endless against the window on the %d-span line: mean %.2f %%, std %.2f %%, max %.2f %%, min %.2f %% of the mean\n",
              spans, 100 * std::fabs(endless.st.filtered.mean / win.st.filtered.mean - 1),
              100 * std::fabs(endless.st.filtered.std_dev / win.st.filtered.std_dev - 1),
              100 * std::fabs(endless.st.filtered.max / win.st.filtered.max - 1),
              100 * std::fabs(endless.st.filtered.min - win.st.filtered.min) / win.st.filtered.mean);
  std::printf("cost per simulated second on the endless line: %.3f ms (%d spans run) against %.3f ms (%d spans run)\n",
              1e3 * endless.wall / endless.sim_time, spans, 1e3 * endless_long.wall / endless_long.sim_time, 10 * spans);
  return 0;
}

int main(int argc, char** argv) { return bench::guarded_main("bench_window", argc, argv, bench_main); }
