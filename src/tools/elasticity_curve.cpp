// elasticity_curve: the static elasticity of a scene along the line, from the model itself.
//   elasticity_curve --scene FILE [--force N] [--step M] [--set key=value ...] [--out FILE.csv]
// A stiff probe collector is pressed up with --force (default 100 N) at every station (eq. 23,
// droppers tension-only, contact only where it pushes) and the static uplift of each contact
// wire under it is written as CSV: x_m, then uplift_<wire>_mm per contact wire (empty where the
// probe does not touch that wire).
#include <CLI/CLI.hpp>
#include <cmath>
#include <iostream>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/output/output_files.hpp"
#include "catenary_sim/core/model/statics.hpp"
#include "cli_checks.hpp"

using namespace catenary_sim;

namespace {
// Each station is a static solve of the whole line: 1e5 stations is a 5 km line at 5 cm.
constexpr double kMaxStations = 1e5;
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The static elasticity of a scene along the line (eq. 23 with a probe collector), as CSV.",
               "elasticity_curve"};
  std::string scene_path, out_path;
  std::vector<std::string> overrides;
  double force = 100.0, step = 0.5;
  app.add_option("--scene", scene_path, "scene YAML")->required()->type_name("FILE");
  app.add_option("--force", force, "probe force pressing up, N")->check(kFinite & CLI::Range(1e-3, 2000.0))->capture_default_str();
  app.add_option("--step", step, "distance between stations, m")->check(kFinite & CLI::Range(1e-3, 100.0))->capture_default_str();
  app.add_option("--set", overrides, "override a scene field (as simulate_pass --set)")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false)
      ->take_all();
  app.add_option("--out", out_path, "CSV file (written whole or not at all); default: standard output")->type_name("FILE");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (!out_path.empty()) check_writable(out_path);
    const Scene scene = load_scene_file(scene_path, overrides);
    const std::vector<double> rises = transition_support_rises(scene);
    const ElasticityProbe probe(scene, force, rises);
    const Model& m = probe.model();
    const double x0 = m.support_x.front(), x1 = m.support_x.back();
    const double stations = std::floor((x1 - x0) / step + 1e-9) + 1.0;
    if (stations > kMaxStations) {
      std::cerr << "elasticity_curve: --step " << step << " gives " << stations << " stations over " << x1 - x0
                << " m; allowed at most " << kMaxStations << " (a longer --step)\n";
      return 2;
    }
    const int n = static_cast<int>(stations) - 1;
    std::ostringstream out;
    out << "x_m";
    for (int wi : m.contact_wires) out << ",uplift_" << m.wires[wi].name << "_mm";
    out << "\n";
    for (int i = 0; i <= n; ++i) {
      const double x = x0 + i * step;
      const std::vector<double> up = probe.uplift(x);
      out << x;
      for (double u : up) {
        out << ",";
        if (std::isfinite(u)) out << u * 1e3;
      }
      out << "\n";
    }
    if (out_path.empty()) std::cout << out.str();
    else write_file_atomically(out_path, out.str());
    std::cerr << "elasticity_curve: " << n + 1 << " stations, probe force " << force << " N; contact-wire supports raised by";
    for (std::size_t s = 0; s < rises.size(); ++s) std::cerr << " " << rises[s] * 1e3;
    std::cerr << " mm (section first/last)\n";
  } catch (const SceneError& e) {
    std::cerr << "elasticity_curve: " << e.what() << "\n";
    return 2;
  } catch (const OutputError& e) {
    std::cerr << "elasticity_curve: " << e.what() << "\n";
    return 2;
  } catch (const std::bad_alloc&) {
    std::cerr << "elasticity_curve: out of memory building the model of '" << scene_path << "'\n";
    return 2;
  }
  return 0;
}
