// The fidelity ladder measured: the reference scene at 250 and 300 km/h for every preset, with the
// moving window off and on, the fast rung with its supports and droppers at q_n and the balanced
// one with them at the step's middle (numerics.supports, numerics.droppers), and the implicit
// integrator as a knob, with DOFs, dt, wall time, real-time factor, and the error
// against `reference` in the 0-20 Hz statistics (mean, std, max, min) and in the 0-200 Hz max.
//   bench_speed_accuracy [scene=config/reference_55m.yaml] [csv=speed_accuracy.csv]
// Errors are relative to the reference value (for the min: relative to the reference mean,
// since the min can be near zero). Wall time is the median of 3 runs for the cheap variants.
#include <cstdio>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "catenary_sim/core/output/output_files.hpp"
#include "pass_errors.hpp"
#include "bench_cli.hpp"
#include "guarded_main.hpp"

using bench::PassResult;
using bench::run_pass;

static int bench_main(int argc, char** argv) {
  CLI::App app{"The fidelity ladder measured: every preset at 250 and 300 km/h, its cost and its error against "
               "`reference`.",
               "bench_speed_accuracy"};
  std::string path = bench::kReferenceScene, csv_path = "speed_accuracy.csv";
  bench::add_scene(app, path);
  app.add_option("csv", csv_path, "CSV written, a row per speed and variant")->type_name("FILE")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  // The CSV is written whole at the end (write_file_atomically): a run stopped early leaves the
  // previous file as it was.
  std::ostringstream csv;
  csv << bench::kCsvHeader;
  for (double kmh : {250.0, 300.0}) {
    const PassResult ref = run_pass(path, {"numerics.preset=reference"}, kmh);
    const std::vector<std::pair<std::string, std::vector<std::string>>> variants = {
        {"fast", {"numerics.preset=fast"}},
        {"fast + window", {"numerics.preset=fast", "numerics.window=auto"}},
        {"fast + springs at q_n", {"numerics.preset=fast", "numerics.supports=explicit", "numerics.droppers=explicit"}},
        {"balanced", {"numerics.preset=balanced"}},
        {"balanced + window", {"numerics.preset=balanced", "numerics.window=auto"}},
        {"balanced + springs at middle", {"numerics.preset=balanced", "numerics.supports=implicit", "numerics.droppers=implicit"}},
        {"accurate", {"numerics.preset=accurate"}},
        {"accurate + window", {"numerics.preset=accurate", "numerics.window=auto"}},
        {"implicit h=0.25 dt=1ms", {"numerics.integrator=implicit", "numerics.dt=0.001"}},
        {"implicit h=0.125 dt=1ms", {"numerics.integrator=implicit", "numerics.element_length=0.125", "numerics.dt=0.001"}},
    };
    std::printf("\n%.0f km/h (reference: %d DOFs, dt %.4f ms, %.2f s wall, %.1fx real time; std %.2f N, max %.2f N, 200 Hz max %.2f N)\n",
                kmh, ref.dofs, ref.dt * 1e3, ref.wall, ref.rtf, ref.s20.filtered.std_dev, ref.s20.filtered.max,
                ref.s200.filtered.max);
    std::printf("%-28s %6s %8s %8s %8s | %7s %7s %7s %7s | %8s\n", "variant", "DOFs", "dt_ms", "wall_s", "RTF", "mean%",
                "std%", "max%", "min%", "max200%");
    for (const auto& [label, ov] : variants) {
      const PassResult r = run_pass(path, ov, kmh, 3);
      const bench::StatErrors e = bench::stat_errors(r, ref);
      std::printf("%-28s %6d %8.4f %8.4f %8.1f | %7.2f %7.2f %7.2f %7.2f | %8.2f\n", label.c_str(), r.dofs, r.dt * 1e3,
                  r.wall, r.rtf, e.mean, e.std_dev, e.max, e.min, e.max200);
      bench::csv_row(csv, kmh, label, r.dofs, r.dt, r.wall, r.rtf, e);
    }
  }
  catenary_sim::write_file_atomically(csv_path, csv.str());
  std::printf("\nwrote %s\n", csv_path.c_str());
  return 0;
}

int main(int argc, char** argv) { return bench::guarded_main("bench_speed_accuracy", argc, argv, bench_main); }
