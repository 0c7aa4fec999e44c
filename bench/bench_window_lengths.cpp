// How long the moving window must be, ahead and behind, against train speed: the data behind
// `numerics.window: auto` (window.cpp). The reference catenary on a 42-span line, balanced preset,
// statistics over spans 16-35. The reference for each speed is a generous window (5 spans ahead,
// 14 behind), not the full line: a finite full line is not the line that goes on that a window
// stands for (waves come back from its anchors, at c - V from the one behind, long after they
// left), and the question is how short the window can be before its own ends show. Then windows
// with one length varied and the other generous. Prints, per run, the change of the 0-20 Hz
// statistics (mean, std and max relative; min relative to the mean, %) and the largest of them,
// and the lengths the auto rule picks at that speed.
//   bench_window_lengths [speeds_kmh=150,250,300,350] [auto]   (auto: only the auto rule's rows)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "../test/support/scenes.hpp"
#include "bench_cli.hpp"
#include "guarded_main.hpp"

using namespace catenary_sim;

namespace {

const std::string& kScene = test_scenes::kReference;

ForceStatistics run(std::vector<std::string> ov) {
  Simulation sim(load_scene_file(kScene, ov));
  const Model& m = sim.model();
  PassRecorder rec(m);
  rec.record(m, sim.state());
  while (sim.step() == StepStatus::kOk) rec.record(m, sim.state());
  return rec.statistics(m)[0].filtered;
}

void print_change(double kmh, const char* varied, double ahead, double behind, const ForceStatistics& w, const ForceStatistics& f) {
  const double mean = 100 * std::fabs(w.mean / f.mean - 1), sd = 100 * std::fabs(w.std_dev / f.std_dev - 1),
               mx = 100 * std::fabs(w.max / f.max - 1), mn = 100 * std::fabs(w.min - f.min) / f.mean;
  std::printf("%6.0f %-7s %6.2f %6.2f | %6.3f %6.3f %6.3f %6.3f | %6.3f\n", kmh, varied, ahead, behind, mean, sd, mx, mn,
              std::max({mean, sd, mx, mn}));
  std::fflush(stdout);
}

// The speeds of a comma-separated list (km/h) into *speeds; an error message, or empty.
std::string read_speeds(const std::string& text, std::vector<double>* speeds) {
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::size_t used = 0;
    double v = 0.0;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (item.empty() || used != item.size() || !(v > 0.0 && v <= 3.6 * kMaxTrainSpeed))
      return "'" + item + "' is not a speed in (0, " + std::to_string(static_cast<int>(3.6 * kMaxTrainSpeed)) + "] km/h";
    speeds->push_back(v);
  }
  return speeds->empty() ? "no speed given" : std::string();
}

}  // namespace

static int bench_main(int argc, char** argv) {
  CLI::App app{"How long the moving window must be, ahead and behind, against train speed: the data behind "
               "`numerics.window: auto`.",
               "bench_window_lengths"};
  std::string speed_list = "150,250,300,350", rows;
  app.add_option("speeds_kmh", speed_list, "train speeds, km/h, comma separated")
      ->check(CLI::Validator(
          [](std::string& text) {
            std::vector<double> v;
            return read_speeds(text, &v);
          },
          "KMH,..."))
      ->capture_default_str();
  app.add_option("rows", rows, "auto: only the auto rule's rows (default: the window lengths varied too)")
      ->check(CLI::IsMember({"auto"}));
  CLI11_PARSE(app, argc, argv);
  std::vector<double> speeds;
  read_speeds(speed_list, &speeds);
  const double span = 55.0;
  const std::vector<double> aheads = {1.0, 1.5, 2.0, 2.5, 3.0, 4.0}, behinds = {1.0, 2.0, 3.0, 4.0, 6.0};
  const double generous_ahead = 5.0, generous_behind = 14.0;  // spans
  std::printf("%6s %-7s %6s %6s | %6s %6s %6s %6s | %6s  (lengths in spans, changes in %%)\n", "km/h", "varied", "ahead",
              "behind", "mean", "std", "max", "min", "worst");
  for (double kmh : speeds) {
    std::vector<std::string> base = {"line.span_count=42", "numerics.preset=balanced", "output.analysis_spans=[16,36]",
                                     "train.speed_kmh=" + std::to_string(kmh)};
    auto window = [&](double ahead, double behind) {
      std::vector<std::string> ov = base;
      ov.push_back("numerics.window={ahead: " + std::to_string(ahead * span) + ", behind: " + std::to_string(behind * span) + "}");
      return run(ov);
    };
    const ForceStatistics ref = window(generous_ahead, generous_behind);
    const bool sweep = rows != "auto";
    for (double a : sweep ? aheads : std::vector<double>{}) print_change(kmh, "ahead", a, generous_behind, window(a, generous_behind), ref);
    for (double b : sweep ? behinds : std::vector<double>{}) print_change(kmh, "behind", generous_ahead, b, window(generous_ahead, b), ref);
    std::vector<std::string> ov = base;
    ov.push_back("numerics.window=auto");
    Simulation sim(load_scene_file(kScene, ov));
    double ahead = 0, behind = 0;
    window_lengths(sim.model(), sim.state().speed, &ahead, &behind);
    print_change(kmh, "auto", ahead / span, behind / span, run(ov), ref);
  }
  return 0;
}

int main(int argc, char** argv) { return bench::guarded_main("bench_window_lengths", argc, argv, bench_main); }
