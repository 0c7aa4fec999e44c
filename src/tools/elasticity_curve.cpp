// elasticity_curve: the static elasticity of a scene along the line, from the model itself.
//   elasticity_curve --scene FILE [--force N] [--step M] [--set key=value ...] [--out FILE.csv]
// A stiff probe collector is pressed up with --force (default 100 N) at every station (eq. 23,
// droppers tension-only, contact only where it pushes) and the static uplift of each contact
// wire under it is written as CSV: x_m, then uplift_<wire>_mm per contact wire (empty where the
// probe does not touch that wire).
#include <cmath>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "catenary_sim/core/model.hpp"
#include "catenary_sim/core/statics.hpp"

using namespace catenary_sim;

int main(int argc, char** argv) {
  std::string scene_path, out_path;
  std::vector<std::string> overrides;
  double force = 100.0, step = 0.5;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "elasticity_curve: " << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    auto number = [&](double lo, double hi) {
      const std::string v = value();
      char* end = nullptr;
      const double d = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !(d > lo && d <= hi)) {
        std::cerr << "elasticity_curve: " << a << " '" << v << "': expected a number in (" << lo << ", " << hi << "]\n";
        std::exit(2);
      }
      return d;
    };
    if (a == "--scene") scene_path = value();
    else if (a == "--out") out_path = value();
    else if (a == "--set") overrides.push_back(value());
    else if (a == "--force") force = number(0.0, 2000.0);
    else if (a == "--step") step = number(0.0, 100.0);
    else {
      std::cerr << "usage: elasticity_curve --scene FILE [--force N] [--step M] [--set key=value ...] [--out FILE.csv]\n";
      return 2;
    }
  }
  if (scene_path.empty()) {
    std::cerr << "elasticity_curve: --scene is required\n";
    return 2;
  }
  try {
    const Scene scene = load_scene_file(scene_path, overrides);
    const std::vector<double> rises = transition_support_rises(scene);
    const ElasticityProbe probe(scene, force, rises);
    const Model& m = probe.model();
    std::ofstream file;
    if (!out_path.empty()) {
      file.open(out_path);
      if (!file) {
        std::cerr << "elasticity_curve: cannot write '" << out_path << "'\n";
        return 2;
      }
    }
    std::ostream& out = out_path.empty() ? std::cout : file;
    out << "x_m";
    for (int wi : m.contact_wires) out << ",uplift_" << m.wires[wi].name << "_mm";
    out << "\n";
    const double x0 = m.support_x.front(), x1 = m.support_x.back();
    const int n = static_cast<int>(std::floor((x1 - x0) / step + 1e-9));
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
    std::cerr << "elasticity_curve: " << n + 1 << " stations, probe force " << force << " N; contact-wire supports raised by";
    for (std::size_t s = 0; s < rises.size(); ++s) std::cerr << " " << rises[s] * 1e3;
    std::cerr << " mm (section first/last)\n";
  } catch (const SceneError& e) {
    std::cerr << "elasticity_curve: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
