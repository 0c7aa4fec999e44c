// The 3-D line's cost: the reference pass (config/reference_55m.yaml, 300 km/h, accurate preset)
// as the 2-D model and with a lateral plane (stagger alone; stagger with a turbulent cross wind,
// as config/reference_55m_3d.yaml), bare and with the recorders simulate_pass runs, in one
// process with the repetitions interleaved, so the real-time factors compare as ratios.
// Then the moving window on a long line: 2-D and 3-D passes with numerics.window=auto on
// `long_spans` spans and on 20, bare step, interleaved. In a steady wind (stagger + 20 m/s) the
// 3-D window's cost per simulated second must not grow with the line (its lateral plane is
// windowed as the vertical one) and compares with the 2-D window's as a ratio; in a turbulent wind
// a finite line's lateral plane steps the whole line (LateralModel::windowed), and its cost grows.
// long_spans 0 skips it. Then, for `seeds` seeds of the turbulent wind (0 skips it), the contact
// point's turbulent motion (its position in the turbulent wind less that in the steady mean wind)
// on 40 spans, balanced preset, full line against numerics.window=auto (which keeps the whole
// lateral plane in a turbulent wind: the two should agree).
//   bench_lateral [repetitions=5] [long_spans=100] [seeds=0]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
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

// 2-D and 3-D windowed passes on `spans` spans and on 20, the repetitions interleaved.
void run_windowed(int reps, int spans, const std::vector<std::string>& steady, const std::vector<std::string>& windy) {
  const std::string path = test_scenes::kReference;
  struct Variant {
    std::string label;
    int spans;
    const std::vector<std::string>* lateral;
  };
  const std::vector<Variant> variants{{"2-D window", spans, nullptr},
                                      {"3-D stagger + steady wind, window", spans, &steady},
                                      {"3-D turbulent (lateral: whole line)", spans, &windy},
                                      {"2-D window", 20, nullptr},
                                      {"3-D stagger + steady wind, window", 20, &steady},
                                      {"3-D turbulent (lateral: whole line)", 20, &windy}};
  std::vector<Scene> scenes;
  for (const Variant& v : variants) {
    std::vector<std::string> ov{"line.span_count=" + std::to_string(v.spans), "numerics.window=auto"};
    if (v.lateral) ov.insert(ov.end(), v.lateral->begin(), v.lateral->end());
    scenes.push_back(load_scene_file(path, ov));
  }
  std::vector<std::vector<double>> walls(variants.size());
  std::vector<double> sim_time(variants.size());
  std::vector<int> dofs(variants.size());
  for (int r = 0; r < reps; ++r)
    for (std::size_t i = 0; i < variants.size(); ++i) {
      Simulation sim(scenes[i]);
      const auto t0 = std::chrono::steady_clock::now();
      while (sim.step() == StepStatus::kOk) {
      }
      walls[i].push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      sim_time[i] = sim.state().time;
      dofs[i] = sim.model().n_dof + (sim.model().lateral ? sim.model().lateral->n : 0);
    }
  std::printf("\nmoving window (numerics.window=auto), bare step\n");
  std::printf("%-34s %6s %6s %9s %10s %10s %8s %12s %10s\n", "variant", "spans", "DOFs", "sim_s", "wall_med_s", "wall_min_s",
              "RTF_med", "ms/sim_s_med", "RTF/2-D");
  std::vector<double> ms(variants.size());
  double base_rtf = 0.0;
  for (std::size_t i = 0; i < variants.size(); ++i) {
    std::sort(walls[i].begin(), walls[i].end());
    const double med = walls[i][walls[i].size() / 2], rtf = sim_time[i] / med;
    if (!variants[i].lateral) base_rtf = rtf;  // the 2-D row just above: same line
    ms[i] = 1e3 * med / sim_time[i];
    std::printf("%-34s %6d %6d %9.2f %10.4f %10.4f %8.1f %12.3f %10.3f\n", variants[i].label.c_str(), variants[i].spans,
                dofs[i], sim_time[i], med, walls[i].front(), rtf, ms[i], rtf / base_rtf);
  }
  std::printf("cost per simulated second, %d spans against 20: 2-D %.3f, 3-D steady wind %.3f, 3-D turbulent %.3f\n", spans,
              ms[0] / ms[3], ms[1] / ms[4], ms[2] / ms[5]);
}

// The contact point's turbulent motion (position in the turbulent wind less in the steady mean
// wind) on the full line and with the window, over spans 4 to 36 of 40.
void turbulent_motion(int seed, std::vector<std::string> windy) {
  const std::string path = test_scenes::kReference;
  windy.insert(windy.end(), {"numerics.preset=balanced", "line.span_count=40"});
  std::vector<std::string> full = windy, steady = windy, window = windy;
  full.push_back("wind.turbulence.seed=" + std::to_string(seed));
  window.insert(window.end(), {"wind.turbulence.seed=" + std::to_string(seed), "numerics.window=auto"});
  steady.push_back("wind.turbulence=null");
  Simulation a(load_scene_file(path, full)), b(load_scene_file(path, window)), c(load_scene_file(path, steady));
  double sa = 0, sb = 0, sd = 0, ma = 0, mb = 0;
  long n = 0;
  while (a.step() == StepStatus::kOk && b.step() == StepStatus::kOk && c.step() == StepStatus::kOk) {
    const double ya = a.state().lateral.collector_lateral[0], yb = b.state().lateral.collector_lateral[0],
                 yc = c.state().lateral.collector_lateral[0], x = a.state().front;
    if (x < 4 * 55.0 || x > 36 * 55.0 || !std::isfinite(ya) || !std::isfinite(yb) || !std::isfinite(yc)) continue;
    sa += (ya - yc) * (ya - yc);
    sb += (yb - yc) * (yb - yc);
    sd += (yb - ya) * (yb - ya);
    ma = std::max(ma, std::fabs(ya - yc));
    mb = std::max(mb, std::fabs(yb - yc));
    ++n;
  }
  if (seed == 1)
    std::printf("\ncontact point's turbulent motion (mm), 40 spans, balanced: rms full / window, max full / window, "
                "rms of window - full\n");
  std::printf("seed %d: rms %.2f / %.2f, max %.2f / %.2f, rms difference %.2f (%ld steps)\n", seed, 1e3 * std::sqrt(sa / n),
              1e3 * std::sqrt(sb / n), 1e3 * ma, 1e3 * mb, 1e3 * std::sqrt(sd / n), n);
}

}  // namespace

static int bench_main(int argc, char** argv) {
  CLI::App app{"The 3-D line's cost: the reference pass as the 2-D model and with a lateral plane, then the "
               "moving window on a long line and the turbulent motion with and without it.",
               "bench_lateral"};
  int reps = 5, long_spans = 100, seeds = 0;
  bench::add_repetitions(app, reps);
  app.add_option("long_spans", long_spans, "spans of the long line the window runs on (0 skips it)")
      ->check(CLI::Range(0, 10000))
      ->capture_default_str();
  app.add_option("seeds", seeds, "seeds of the turbulent wind for the contact point's motion (0 skips it)")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  const std::string path = test_scenes::kReference;
  struct Variant {
    std::string label;
    std::vector<std::string> overrides;
    bool record;
  };
  const std::vector<std::string> stagger{"stagger.contact_wire=[0.3,-0.3]", "stagger.messenger=[0.0]",
                                         "stagger.steady_arm_stiffness=2e5"};
  std::vector<std::string> windy = stagger;
  for (const char* o : {"wind.speed=20", "wind.turbulence.intensity=0.15", "wind.turbulence.seed=1"}) windy.push_back(o);
  const std::vector<Variant> variants{{"2-D", {}, false},
                                      {"3-D stagger", stagger, false},
                                      {"3-D stagger + turbulent wind", windy, false},
                                      {"2-D + recorders", {}, true},
                                      {"3-D stagger + wind + recorders", windy, true}};
  std::vector<Scene> scenes;
  for (const Variant& v : variants) scenes.push_back(load_scene_file(path, v.overrides));
  std::vector<std::vector<double>> walls(variants.size());
  std::vector<double> sim_time(variants.size()), dt(variants.size());
  std::vector<int> dofs(variants.size());
  for (int r = 0; r < reps; ++r)
    for (std::size_t i = 0; i < variants.size(); ++i) {
      Simulation sim(scenes[i]);  // building (statics, wind field) is not timed: only the pass
      const Model& m = sim.model();
      std::unique_ptr<PassRecorder> rec;
      std::unique_ptr<LateralRecorder> lat;
      if (variants[i].record) {
        rec = std::make_unique<PassRecorder>(m, scenes[i].output.sample_rate);
        lat = std::make_unique<LateralRecorder>(m, scenes[i].output.sample_rate);
      }
      const auto t0 = std::chrono::steady_clock::now();
      if (rec) {
        rec->record(m, sim.state());
        lat->record(m, sim.state());
        while (sim.step() == StepStatus::kOk) {
          rec->record(m, sim.state());
          lat->record(m, sim.state());
        }
      } else {
        while (sim.step() == StepStatus::kOk) {
        }
      }
      walls[i].push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      sim_time[i] = sim.state().time;
      dt[i] = m.dt;
      dofs[i] = m.n_dof + (m.lateral ? m.lateral->n : 0);
    }
  std::printf("%-34s %6s %9s %10s %10s %8s %10s\n", "variant", "DOFs", "dt_ms", "wall_med_s", "wall_min_s", "RTF_med", "RTF/2-D");
  double base_rtf = 0.0, base_rec_rtf = 0.0;
  for (std::size_t i = 0; i < variants.size(); ++i) {
    std::sort(walls[i].begin(), walls[i].end());
    const double med = walls[i][walls[i].size() / 2], rtf = sim_time[i] / med;
    if (i == 0) base_rtf = rtf;
    if (i == 3) base_rec_rtf = rtf;
    std::printf("%-34s %6d %9.4f %10.4f %10.4f %8.1f %10.3f\n", variants[i].label.c_str(), dofs[i], dt[i] * 1e3, med,
                walls[i].front(), rtf, rtf / (variants[i].record ? base_rec_rtf : base_rtf));
  }
  std::vector<std::string> steady = stagger;
  steady.push_back("wind.speed=20");
  if (long_spans > 0) run_windowed(reps, long_spans, steady, windy);
  for (int seed = 1; seed <= seeds; ++seed) turbulent_motion(seed, windy);
  return 0;
}

int main(int argc, char** argv) { return bench::guarded_main("bench_lateral", argc, argv, bench_main); }
