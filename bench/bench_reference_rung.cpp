// Choosing the `reference` rung: candidates against a still finer solution. The finest solution is
// the explicit scheme at h = 0.03125 m (automatic dt: the stability limit falls with h, so dt is
// refined with it); every candidate's 0-20 Hz statistics (mean, std, max, min) and 0-200 Hz max are
// compared with it, with its wall time, on the reference scene at 250 and 300 km/h.
//   bench_reference_rung [scene=config/reference_55m.yaml] [csv=reference_rung.csv] [finest_h=0.03125]
//                        [mode=explicit|all|centred|window|3d|richardson] [field=value ...]
// `window`: the rung with a moving window (numerics.window auto, also the endless line's), against
// the finest solution in the same window, beside the half-step h = 0.1 m rung it replaces there.
// `3d`: the same candidates on a 3-D line, the finest solution with centred damping in both planes
// (at h = 0.03125 m the half-step's dt falls to 2.4 us, 9x below the centred step's, whose limit
// is the half-step's: CentredDamping.*ConvergesAtSecondOrderToTheHalfStepsLimit, the 2-D table).
// Further field=value overrides apply to every pass, the finest included (e.g. train.end=1100 on
// the endless line).
// Errors as in bench_speed_accuracy: relative to the finest value (the min relative to the mean).
// The finest runs take about 10 minutes each: their statistics are kept in <csv>.finest and reused
// when that file exists (delete it after changing the scene or the model).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
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
  CLI::App app{"Choosing the `reference` rung: candidates against a still finer solution, on the reference scene at "
               "250 and 300 km/h.",
               "bench_reference_rung"};
  std::string path = bench::kReferenceScene, csv_path = "reference_rung.csv", finest_h = "0.03125", mode = "explicit";
  std::vector<std::string> overrides;
  bench::add_scene(app, path);
  app.add_option("csv", csv_path, "CSV written, a row per speed and candidate (the finest solution's in <csv>.finest)")
      ->type_name("FILE")
      ->capture_default_str();
  // (kept as written: it is printed and kept in <csv>.finest as given)
  app.add_option("finest_h", finest_h, "element length of the finest solution, m (numerics.element_length)")
      ->check(bench::kFinite & CLI::Range(0.01, 10.0))
      ->capture_default_str();
  app.add_option("mode", mode, "the candidates: explicit, all (explicit and the first five measured), centred (damping), "
                 "window, 3d, or richardson (extrapolated from two explicit meshes)")
      ->check(CLI::IsMember({"explicit", "all", "centred", "window", "3d", "richardson"}))
      ->capture_default_str();
  bench::add_overrides(app, overrides, "overrides of every pass's scene fields, the finest's included");
  CLI11_PARSE(app, argc, argv);
  // The CSV is written whole at the end (write_file_atomically): a run stopped early leaves the
  // previous file as it was (the finest passes' statistics are kept as they come, in .finest).
  std::ostringstream csv;
  csv << bench::kCsvHeader;
  // `explicit`: the first five were measured first (BENCHMARKS.md); the rest refine the explicit
  // scheme's dt at h = 0.125 m and try h = 0.1 m. `all` for the first five too, or `centred` for
  // the explicit step with centred damping (numerics.damping) beside the half-step rungs it
  // replaces.
  const bool all = mode == "all";
  std::vector<std::pair<std::string, std::vector<std::string>>> candidates = {
      {"explicit h=0.125", {"numerics.element_length=0.125"}},
      {"explicit h=0.125 dt=auto/2", {"numerics.element_length=0.125", "numerics.safety_factor=0.45"}},
      {"explicit h=0.125 dt=auto/4", {"numerics.element_length=0.125", "numerics.safety_factor=0.225"}},
      {"explicit h=0.1", {"numerics.element_length=0.1"}},
      {"explicit h=0.1 dt=auto/2", {"numerics.element_length=0.1", "numerics.safety_factor=0.45"}},
  };
  if (all)
    candidates.insert(
        candidates.begin(),
        {{"explicit h=0.0625 (old reference)", {"numerics.element_length=0.0625"}},
         {"implicit h=0.125 dt=1ms", {"numerics.integrator=implicit", "numerics.element_length=0.125", "numerics.dt=0.001"}},
         {"implicit h=0.125 dt=0.5ms", {"numerics.integrator=implicit", "numerics.element_length=0.125", "numerics.dt=0.0005"}},
         {"implicit h=0.0625 dt=0.5ms",
          {"numerics.integrator=implicit", "numerics.element_length=0.0625", "numerics.dt=0.0005"}}});
  if (mode == "window" || mode == "3d")
    candidates = {
        {"half-step h=0.1 (the rung it replaces here)", {"numerics.element_length=0.1", "numerics.damping=half_step"}},
        {"centred h=0.0625 (the rung)", {"numerics.element_length=0.0625", "numerics.damping=centred"}},
    };
  if (mode == "centred")
    candidates = {
        {"half-step h=0.0625 (the rung of 25f35a6)", {"numerics.element_length=0.0625", "numerics.damping=half_step"}},
        {"half-step h=0.1 (the rung before)", {"numerics.element_length=0.1", "numerics.damping=half_step"}},
        {"centred h=0.1", {"numerics.element_length=0.1", "numerics.damping=centred"}},
        {"centred h=0.08", {"numerics.element_length=0.08", "numerics.damping=centred"}},
        {"centred h=0.07", {"numerics.element_length=0.07", "numerics.damping=centred"}},
        {"centred h=0.0625 (the new rung)", {"numerics.element_length=0.0625", "numerics.damping=centred"}},
        {"centred h=0.0625 dt=auto/2", {"numerics.element_length=0.0625", "numerics.damping=centred", "numerics.safety_factor=0.45"}},
    };
  // Overrides of every pass: the window's, then the command line's.
  std::vector<std::string> every;
  if (mode == "window") every.push_back("numerics.window=auto");
  every.insert(every.end(), overrides.begin(), overrides.end());
  for (auto& [label, ov] : candidates) ov.insert(ov.end(), every.begin(), every.end());
  // Finest statistics kept from an earlier run: kmh -> mean, std, max, min, max200, dofs, dt, wall.
  std::map<double, std::vector<double>> kept;
  {
    std::ifstream in(csv_path + ".finest");
    std::string line;
    while (std::getline(in, line)) {
      std::istringstream ls(line);
      std::vector<double> v;
      for (std::string x; std::getline(ls, x, ',');) v.push_back(std::stod(x));
      if (v.size() == 9) kept[v[0]] = std::vector<double>(v.begin() + 1, v.end());
    }
  }
  // Richardson extrapolation of the statistics from two explicit meshes (h_a < h_b): the
  // explicit scheme's error in a statistic is c h^2 + O(h^4) here (its dt falls with h, so the
  // time error is of higher order), so S_a + (S_a - S_b) / ((h_b / h_a)^2 - 1) cancels the h^2 term.
  // Give `richardson` as mode to measure these instead of the candidates above.
  const bool richardson = mode == "richardson";
  const std::vector<std::pair<double, double>> pairs = {{0.125, 0.25}, {0.1, 0.2}, {0.1, 0.125}, {0.0625, 0.125}};
  if (richardson) candidates.clear();
  for (double kmh : {250.0, 300.0}) {
    PassResult fine;
    if (kept.count(kmh)) {
      const std::vector<double>& k = kept[kmh];
      fine.s20.filtered.mean = k[0];
      fine.s20.filtered.std_dev = k[1];
      fine.s20.filtered.max = k[2];
      fine.s20.filtered.min = k[3];
      fine.s200.filtered.max = k[4];
      fine.dofs = static_cast<int>(k[5]);
      fine.dt = k[6];
      fine.wall = k[7];
    } else {
      std::vector<std::string> ov = {"numerics.element_length=" + finest_h,
                                     mode == "3d" ? "numerics.damping=centred" : "numerics.damping=half_step"};
      ov.insert(ov.end(), every.begin(), every.end());
      fine = run_pass(path, ov, kmh);
      std::ofstream out(csv_path + ".finest", std::ios::app);
      out.precision(17);
      out << kmh << "," << fine.s20.filtered.mean << "," << fine.s20.filtered.std_dev << "," << fine.s20.filtered.max << ","
          << fine.s20.filtered.min << "," << fine.s200.filtered.max << "," << fine.dofs << "," << fine.dt << "," << fine.wall
          << "\n";
    }
    std::printf("\n%.0f km/h, finest: explicit h=%s m, %d DOFs, dt %.4f ms, %.1f s wall; std %.3f N, max %.3f N, 200 Hz max %.3f N\n",
                kmh, finest_h.c_str(), fine.dofs, fine.dt * 1e3, fine.wall, fine.s20.filtered.std_dev,
                fine.s20.filtered.max, fine.s200.filtered.max);
    std::printf("%-30s %6s %8s %8s %8s | %7s %7s %7s %7s | %8s\n", "candidate", "DOFs", "dt_ms", "wall_s", "RTF", "mean%",
                "std%", "max%", "min%", "max200%");
    for (const auto& [label, ov] : candidates) {
      const PassResult r = run_pass(path, ov, kmh);
      const bench::StatErrors e = bench::stat_errors(r, fine);
      std::printf("%-30s %6d %8.4f %8.2f %8.2f | %7.3f %7.3f %7.3f %7.3f | %8.3f\n", label.c_str(), r.dofs, r.dt * 1e3,
                  r.wall, r.rtf, e.mean, e.std_dev, e.max, e.min, e.max200);
      std::fflush(stdout);
      bench::csv_row(csv, kmh, label, r.dofs, r.dt, r.wall, r.rtf, e);
    }
    for (const auto& [ha, hb] : richardson ? pairs : std::vector<std::pair<double, double>>{}) {
      std::ostringstream label;
      label << "richardson h=" << ha << "+" << hb;
      auto with_h = [&](double h) {
        std::vector<std::string> ov = {"numerics.element_length=" + std::to_string(h)};
        ov.insert(ov.end(), every.begin(), every.end());
        return ov;
      };
      const PassResult a = run_pass(path, with_h(ha), kmh), b = run_pass(path, with_h(hb), kmh);
      const double q = 1.0 / ((hb / ha) * (hb / ha) - 1.0);
      auto ex = [&](double sa, double sb) { return sa + (sa - sb) * q; };
      PassResult x;  // the extrapolated statistics
      x.s20.filtered.mean = ex(a.s20.filtered.mean, b.s20.filtered.mean);
      x.s20.filtered.std_dev = ex(a.s20.filtered.std_dev, b.s20.filtered.std_dev);
      x.s20.filtered.max = ex(a.s20.filtered.max, b.s20.filtered.max);
      x.s20.filtered.min = ex(a.s20.filtered.min, b.s20.filtered.min);
      x.s200.filtered.max = ex(a.s200.filtered.max, b.s200.filtered.max);
      const bench::StatErrors e = bench::stat_errors(x, fine);
      const double wall = a.wall + b.wall;
      std::printf("%-30s %6d %8.4f %8.2f %8.2f | %7.4f %7.4f %7.4f %7.4f | %8.4f\n", label.str().c_str(), a.dofs + b.dofs,
                  a.dt * 1e3, wall, a.rtf * a.wall / wall, e.mean, e.std_dev, e.max, e.min, e.max200);
      std::fflush(stdout);
      bench::csv_row(csv, kmh, label.str(), a.dofs + b.dofs, a.dt, wall, a.rtf * a.wall / wall, e);
    }
  }
  catenary_sim::write_file_atomically(csv_path, csv.str());
  std::printf("\nwrote %s\n", csv_path.c_str());
  return 0;
}

int main(int argc, char** argv) { return bench::guarded_main("bench_reference_rung", argc, argv, bench_main); }
