// elasticity_curve: the static elasticity of a scene along the line, from the model itself.
//   elasticity_curve --scene FILE [--force N] [--step M] [--set key=value ...] [--out FILE.csv]
// A stiff probe collector is pressed up with --force (default 100 N) at every station (eq. 23,
// droppers tension-only, contact only where it pushes) and the static uplift of each contact
// wire under it is written as CSV: x_m, then uplift_<wire>_mm per contact wire (empty where the
// probe does not touch that wire). --spans FILE.csv adds the elasticity's range and uniformity
// (EN 50119's (max - min) / (max + min)) over each span of each contact wire. A 3-D scene's plan
// is designed too, and refused where simulate_pass would refuse it.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include "catenary_sim/core/model/lateral.hpp"
#include "catenary_sim/core/model/model.hpp"
#include "catenary_sim/core/output/elasticity_uniformity.hpp"
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
  std::string scene_path, out_path, spans_path;
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
  app.add_option("--spans", spans_path,
                 "CSV of the elasticity over each span of each contact wire: its min, max, mean and uniformity "
                 "(max - min) / (max + min) (written whole or not at all)")
      ->type_name("FILE");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (!out_path.empty()) check_writable(out_path);
    if (!spans_path.empty()) check_writable(spans_path);
    const Scene scene = load_scene_file(scene_path, overrides);
    const std::vector<double> rises = transition_support_rises(scene);
    const ElasticityProbe probe(scene, force, rises);
    const Model& m = probe.model();
    // A 3-D line's plan is part of its design (the bridles' registrations, the wires inside the
    // working width): what simulate_pass refuses there is refused here, though the elasticity is
    // the vertical plane's alone.
    if (scene.lateral()) check_lateral_design(m);
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
    std::vector<double> xs;
    std::vector<std::vector<double>> elasticity(m.contact_wires.size());  // m/N per contact wire
    for (int i = 0; i <= n; ++i) {
      const double x = x0 + i * step;
      const std::vector<double> up = probe.uplift(x);
      xs.push_back(x);
      for (std::size_t k = 0; k < up.size(); ++k) elasticity[k].push_back(up[k] / force);
      out << x;
      for (double u : up) {
        out << ",";
        if (std::isfinite(u)) out << u * 1e3;
      }
      out << "\n";
    }
    if (out_path.empty()) std::cout << out.str();
    else write_file_atomically(out_path, out.str());
    // A span ending at its section's anchor (held, elasticity 0) is listed but left out of the
    // summary: its uniformity is 100 % by construction, not a property of the design.
    std::ostringstream spans;
    spans << "wire,span,start_m,end_m,at_anchor,samples,min_mm_per_N,max_mm_per_N,mean_mm_per_N,uniformity_percent\n";
    for (std::size_t k = 0; k < m.contact_wires.size(); ++k) {
      const Wire& w = m.wires[m.contact_wires[k]];
      double lo = 1.0, hi = 0.0;
      int counted = 0;
      for (const SpanElasticity& s : elasticity_by_span(xs, elasticity[k], m.support_x)) {
        const bool anchor = std::fabs(s.start - w.x.front()) < 1e-6 || std::fabs(s.end - w.x.back()) < 1e-6;
        spans << w.name << "," << s.span << "," << s.start << "," << s.end << "," << anchor << "," << s.samples << ","
              << s.min * 1e3 << "," << s.max * 1e3 << "," << s.mean * 1e3 << "," << s.uniformity * 100.0 << "\n";
        if (anchor) continue;
        lo = std::min(lo, s.uniformity);
        hi = std::max(hi, s.uniformity);
        ++counted;
      }
      if (counted > 0)
        std::cerr << "elasticity_curve: " << w.name << ": uniformity (max - min) / (max + min) " << lo * 100.0 << "-"
                  << hi * 100.0 << " % over its " << counted << " spans away from its anchors\n";
    }
    if (!spans_path.empty()) write_file_atomically(spans_path, spans.str());
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
