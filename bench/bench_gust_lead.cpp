// The endless line in a turbulent wind: what the lateral plane's gust lead (numerics.gust_lead)
// buys and costs. The endless reference line, staggered +-0.3 m in reference_55m_3d.yaml's
// turbulent 20 m/s cross wind, balanced preset, 300 km/h, train front from 500 m to 5500 m, against
// a finite 104-span line whose whole lateral plane is stepped, in the same realisation of the wind
// (both fields start at station 0 with the same time grid; make_wind_field draws point by point).
// The leads stepped on their own (numerics.gust_lead_step implicit), and the auto lead once more
// stepped with the lateral window (explicit). Per seed and lead: the contact point's turbulent
// motion (its position less that of the finite line in the steady mean wind), rms on the finite
// line and on the endless one, and the rms of their difference, over the stations the pantograph reaches after the longest lead has run its
// course; then each run's wall time per simulated second (the runs of one seed interleaved, so
// they compare as ratios; the 2-D endless line for scale).
//   bench_gust_lead [seeds=4]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "../test/support/scenes.hpp"
#include "bench_cli.hpp"
#include "guarded_main.hpp"

using namespace catenary_sim;

namespace {

const std::vector<std::string> kLine = {"numerics.preset=balanced", "train.start=500", "train.end=5500"};

std::vector<std::string> windy(int seed) {
  return {"stagger.contact_wire=[0.3,-0.3]", "stagger.messenger=[0.0]", "stagger.steady_arm_stiffness=2.0e5",
          "wind.speed=20", "wind.direction=90", "wind.contact_wire.diameter=0.0122", "wind.messenger.diameter=0.0105",
          "wind.turbulence.intensity=0.15", "wind.turbulence.length_scale=50", "wind.turbulence.coherence_decay=10",
          "wind.turbulence.seed=" + std::to_string(seed)};
}

Scene scene(bool endless, const std::vector<std::string>& extra) {
  std::vector<std::string> ov = kLine;
  ov.insert(ov.end(), extra.begin(), extra.end());
  if (!endless) ov.insert(ov.end(), {"line.span_count=104", "numerics.window=auto"});
  return load_scene_file(endless ? test_scenes::kReferenceEndless
                                 : test_scenes::kReference,
                         ov);
}

struct Run {
  std::string label;
  std::unique_ptr<Simulation> sim;
  double wall = 0.0, sum2 = 0.0, diff2 = 0.0;  // s; m^2 summed
};

}  // namespace

static int bench_main(int argc, char** argv) {
  CLI::App app{"The endless line in a turbulent wind: what the lateral plane's gust lead (numerics.gust_lead) buys "
               "and costs.",
               "bench_gust_lead"};
  int seeds = 4;
  app.add_option("seeds", seeds, "seeds of the turbulent wind, each a row per lead")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  const std::vector<std::string> leads = {"0", "5", "10", "auto", "30"};
  std::printf("endless line in a turbulent wind against the finite line, balanced, 300 km/h; turbulent motion of the "
              "contact point (mm)\n");
  std::printf("%4s %-26s %9s %11s %9s %8s %14s\n", "seed", "run", "lead_s", "rms_motion", "ratio", "rms_diff",
              "ms/sim_s");
  for (int seed = 1; seed <= seeds; ++seed) {
    std::vector<Run> runs;
    auto add = [&](const std::string& label, Scene s) {
      runs.push_back(Run{label, std::make_unique<Simulation>(std::move(s))});
    };
    add("finite, whole lateral plane", scene(false, windy(seed)));
    std::vector<std::string> steady = windy(seed);
    steady.push_back("wind.turbulence=null");
    add("finite, steady wind", scene(false, steady));
    for (const std::string& lead : leads) {
      std::vector<std::string> ov = windy(seed);
      ov.push_back("numerics.gust_lead=" + lead);
      add("endless, gust_lead " + lead, scene(true, ov));
    }
    {
      std::vector<std::string> ov = windy(seed);
      ov.push_back("numerics.gust_lead_step=explicit");
      add("endless, auto, explicit", scene(true, ov));
    }
    add("endless 2-D", scene(true, {}));
    double longest = 0.0;
    for (const Run& r : runs)
      if (r.sim->model().lateral) longest = std::max(longest, r.sim->model().lateral->gust_lead);
    const double from = 500.0 + longest * runs[0].sim->state().speed + 110.0;
    long n = 0;
    while (true) {
      bool ok = true;
      for (Run& r : runs) {
        const auto t0 = std::chrono::steady_clock::now();
        ok &= r.sim->step() == StepStatus::kOk;
        r.wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      }
      if (!ok) break;
      if (runs[0].sim->state().front < from) continue;
      const double reference = runs[0].sim->state().lateral.collector_lateral[0];
      const double calm = runs[1].sim->state().lateral.collector_lateral[0];
      if (!std::isfinite(reference) || !std::isfinite(calm)) continue;
      for (Run& r : runs) {
        if (!r.sim->model().lateral) continue;
        const double y = r.sim->state().lateral.collector_lateral[0];
        r.sum2 += (y - calm) * (y - calm);
        r.diff2 += (y - reference) * (y - reference);
      }
      ++n;
    }
    const double reference_rms = std::sqrt(runs[0].sum2 / n);
    for (const Run& r : runs) {
      const double ms = 1e3 * r.wall / r.sim->state().time;
      if (!r.sim->model().lateral || &r == &runs[1]) {  // (the steady wind: its time only)
        std::printf("%4d %-26s %9s %11s %9s %8s %14.2f\n", seed, r.label.c_str(), "", "", "", "", ms);
        continue;
      }
      const double rms = std::sqrt(r.sum2 / n);
      std::printf("%4d %-26s %9.2f %11.2f %9.3f %8.2f %14.2f\n", seed, r.label.c_str(), r.sim->model().lateral->gust_lead,
                  1e3 * rms, rms / reference_rms, 1e3 * std::sqrt(r.diff2 / n), ms);
    }
  }
  return 0;
}

int main(int argc, char** argv) { return bench::guarded_main("bench_gust_lead", argc, argv, bench_main); }
