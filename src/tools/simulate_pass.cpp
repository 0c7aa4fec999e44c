// simulate_pass: one offline pass of a scene, no ROS master needed.
//   simulate_pass --scene FILE [--speed KMH] [--set key=value ...] --out DIR
// Prints a summary, writes DIR/stats.json and DIR/timeseries.csv.
#include <sys/stat.h>

#include <cerrno>
#include <chrono>
#include <memory>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/statistics.hpp"
#include "catenary_sim/ros/pass_bag.hpp"

using namespace catenary_sim;

namespace {

const char* kUsage =
    "usage: simulate_pass --scene FILE [--speed KMH] [--set key=value ...] --out DIR\n"
    "  --scene FILE     scene YAML (see README.md, e.g. config/reference_55m.yaml)\n"
    "  --speed KMH      train speed in km/h (overrides train.speed / train.speed_kmh)\n"
    "  --set key=value  override a scene field, e.g. --set numerics.element_length=0.125\n"
    "  --out DIR        output directory for stats.json and timeseries.csv (created)\n"
    "  --bag FILE       also write the node's topics into a rosbag (simulation-time stamps)\n"
    "  --bag-rate HZ    rate of /contact_force, /pantograph_state and /tf in the bag (200; 0: every step)\n"
    "  --quiet          print only errors\n";

bool make_dirs(const std::string& path) {
  std::string cur;
  std::stringstream ss(path);
  if (!path.empty() && path[0] == '/') cur = "/";
  for (std::string part; std::getline(ss, part, '/');) {
    if (part.empty()) continue;
    cur += part + "/";
    if (mkdir(cur.c_str(), 0755) != 0 && errno != EEXIST) return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::string scene_path, out_dir, bag_path;
  ros_layer::PassBagOptions bag_options;
  std::vector<std::string> overrides;
  double speed_kmh = std::nan("");
  bool quiet = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](const char* name) -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "simulate_pass: " << name << " needs a value\n" << kUsage;
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--scene") scene_path = value("--scene");
    else if (a == "--out") out_dir = value("--out");
    else if (a == "--set") overrides.push_back(value("--set"));
    else if (a == "--quiet") quiet = true;
    else if (a == "--bag") bag_path = value("--bag");
    else if (a == "--bag-rate") {
      const std::string v = value("--bag-rate");
      char* end = nullptr;
      bag_options.rate = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !std::isfinite(bag_options.rate) || bag_options.rate < 0.0 ||
          bag_options.rate > 1e6) {
        std::cerr << "simulate_pass: --bag-rate '" << v << "': expected Hz in [0, 1e6] (0: every step)\n";
        return 2;
      }
    }
    else if (a == "--speed") {
      const std::string v = value("--speed");
      char* end = nullptr;
      speed_kmh = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !std::isfinite(speed_kmh) || speed_kmh < 0.0 || speed_kmh > 540.0) {
        std::cerr << "simulate_pass: --speed '" << v << "': expected km/h in [0, 540]\n";
        return 2;
      }
    } else if (a == "--help" || a == "-h") {
      std::cout << kUsage;
      return 0;
    } else {
      std::cerr << "simulate_pass: unknown argument '" << a << "'\n" << kUsage;
      return 2;
    }
  }
  if (scene_path.empty() || out_dir.empty()) {
    std::cerr << "simulate_pass: --scene and --out are required\n" << kUsage;
    return 2;
  }

  Scene scene;
  try {
    scene = load_scene_file(scene_path, overrides);
    if (!std::isnan(speed_kmh)) {
      scene.train_speed = speed_kmh / 3.6;
      validate(scene);
    }
  } catch (const SceneError& e) {
    std::cerr << "simulate_pass: " << e.what() << "\n";
    return 2;
  }

  const auto t_build = std::chrono::steady_clock::now();
  std::unique_ptr<Simulation> sim;
  try {
    sim = std::make_unique<Simulation>(scene);
  } catch (const SceneError& e) {
    std::cerr << "simulate_pass: " << e.what() << "\n";
    return 2;
  }
  const Model& m = sim->model();
  PassRecorder recorder(m, scene.output.sample_rate);
  if (!quiet) {
    if (m.endless)
      std::cout << "scene " << scene.name << ": endless line of " << m.endless_span << " m spans (a block of "
                << m.scene.spans.size() << " moves along under the train), ";
    else
      std::cout << "scene " << scene.name << ": " << scene.spans.size() << " spans, " << m.line_length << " m, ";
    std::cout << m.n_dof << " DOFs, dt " << m.dt * 1e3 << " ms (stability limit " << m.dt_critical * 1e3
              << " ms), speed " << scene.train_speed * 3.6 << " km/h" << std::endl;
  }
  for (const std::string& w : m.warnings) std::cerr << "simulate_pass: warning: " << w << "\n";
  if (scene.train_speed <= 0.0 && !quiet)
    std::cout << "note: train speed 0: the pass never ends; nothing to run\n";

  const auto t0 = std::chrono::steady_clock::now();
  StepStatus status = StepStatus::kOk;
  if (!make_dirs(out_dir)) {
    std::cerr << "simulate_pass: cannot create output directory '" << out_dir << "'\n";
    return 2;
  }
  std::unique_ptr<ros_layer::PassBag> bag;
  if (!bag_path.empty()) {
    try {
      bag = std::make_unique<ros_layer::PassBag>(bag_path, bag_options);
    } catch (const std::exception& e) {
      std::cerr << "simulate_pass: --bag '" << bag_path << "': " << e.what() << "\n";
      return 2;
    }
    bag->write(m, sim->state());
  }
  recorder.record(m, sim->state());
  if (scene.train_speed > 0.0) {
    while ((status = sim->step()) == StepStatus::kOk) {
      recorder.record(m, sim->state());
      if (bag) bag->write(m, sim->state());
    }
  }
  if (bag) bag->close();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double build_s = std::chrono::duration<double>(t0 - t_build).count();
  const State& st = sim->state();
  if (status == StepStatus::kDiverged) {
    std::cerr << "simulate_pass: " << sim->status_message() << "\n";
    return 3;
  }

  const std::vector<PantographStatistics> stats = recorder.statistics(m);
  const double rtf = wall > 0.0 ? st.time / wall : std::nan("");

  {
    std::ofstream j(out_dir + "/stats.json");
    RunInfo run;
    run.wall_time_s = wall;
    run.build_time_s = build_s;
    j << statistics_json(m, st, stats, run);
    if (!j) {
      std::cerr << "simulate_pass: cannot write " << out_dir << "/stats.json\n";
      return 2;
    }
  }
  {
    std::ofstream c(out_dir + "/timeseries.csv");
    c << "time_s";
    for (const std::string& col : recorder.columns()) c << "," << col;
    c << "\n" << std::setprecision(9);
    for (const auto& row : recorder.rows()) {
      c << row.time;
      for (double v : row.values) c << "," << v;
      c << "\n";
    }
    if (!c) {
      std::cerr << "simulate_pass: cannot write " << out_dir << "/timeseries.csv\n";
      return 2;
    }
  }

  if (!quiet) {
    std::cout << std::fixed << std::setprecision(2);
    std::cout << "pass: " << st.steps << " steps, " << st.time << " s simulated in " << wall << " s wall ("
              << std::setprecision(1) << rtf << "x real time)\n";
    double x0 = 0.0, x1 = 0.0;
    analysis_section(m, &x0, &x1);
    std::cout << "statistics over " << x0 << "-" << x1 << " m, contact force low-pass " << scene.output.filter_cutoff << " Hz:\n";
    for (const PantographStatistics& s : stats) {
      std::cout << std::setprecision(1) << "  " << s.name << ": mean " << s.filtered.mean << " N, std "
                << s.filtered.std_dev << " N, max " << s.filtered.max << " N, min " << s.filtered.min
                << " N, stat max " << s.filtered.stat_max << " N, stat min " << s.filtered.stat_min
                << " N, contact loss " << std::setprecision(2) << s.contact_loss_percent << " %, max uplift at steady arm "
                << std::setprecision(1) << s.max_uplift_at_support_m * 1e3 << " mm\n"
                << "      unfiltered: max " << s.unfiltered.max << " N, min " << s.unfiltered.min << " N, std "
                << s.unfiltered.std_dev << " N\n";
      if (s.wires.size() > 1)
        for (const WireContactStatistics& w : s.wires)
          std::cout << "      on " << w.wire << ": mean " << w.mean_force << " N, max " << w.max_force << " N, in contact "
                    << w.contact_percent << " % of the time\n";
    }
    std::cout << "wrote " << out_dir << "/stats.json and " << out_dir << "/timeseries.csv\n";
    if (bag) std::cout << "wrote " << bag->messages() << " messages to " << bag_path << "\n";
  }
  return 0;
}
