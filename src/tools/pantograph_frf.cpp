// pantograph_frf: a pantograph model's frequency response at the head (receptance and apparent
// mass), from the model's equations (eq. 9 in the frequency domain) and measured in the simulator
// (the pantograph alone under a rigid wire driven by stepped sines, the force read from the
// contact, eq. 22), as DIR/frf.csv and a Bode plot DIR/frf.png (scripts/plot_frf).
//   pantograph_frf SCENE --pantograph NAME --out DIR [--fmin HZ] [--fmax HZ] [--points N] [--dt S]
//                  [--max-steps N]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "catenary_sim/core/output/output_files.hpp"
#include "catenary_sim/core/analysis/pantograph_frf.hpp"
#include "catenary_sim/tools/package_files.hpp"
#include "catenary_sim/tools/report_launcher.hpp"
#include "../core/util/format.hpp"  // the core's numbers in messages: one way for all
#include "cli_checks.hpp"

using namespace catenary_sim;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Runs /usr/bin/python3 scripts/plot_frf CSV PNG; returns its exit status (or -1, message in *why).
int run_plot(const std::string& csv, const std::string& png, const std::string& title, std::string* why) {
  const std::string script = find_script("plot_frf");
  if (script.empty()) {
    *why = script_not_found("plot_frf");
    return -1;
  }
  const pid_t pid = start_python_script(script, {csv, png, title}, why);
  return pid < 0 ? -1 : pass_report_status(pid, true);
}

double deg(std::complex<double> z) { return std::arg(z) * 180.0 / kPi; }

// The command line.
struct FrfOptions {
  std::string scene_path, name, out_dir;
  std::vector<std::string> overrides;
  double fmin = 0.5, fmax = 20.0, dt = 1e-4, share = 0.5;
  int points = 30;
  // About 6 minutes of the rig at about 1.3e6 steps/s (3.7e10 steps at --dt 1e-7, the default
  // 30 points, were estimated at 8 hours); the default run at dt 1e-4 takes 3.7e7.
  double max_steps = 5e8;
  bool no_plot = false;
};

// Parses argv into *o; returns -1 to go on, else the exit code (--help: 0; bad flags: CLI11's).
int parse_options(int argc, char** argv, FrfOptions* o) {
  CLI::App app{"A pantograph model's frequency response at the head: analytic (eq. 9) and measured on a simulated "
               "rig (stepped sines, force from the contact), as CSV and a Bode plot.",
               "pantograph_frf"};
  app.add_option("scene", o->scene_path, "scene YAML")->required()->type_name("SCENE");
  app.add_option("--pantograph", o->name, "name of the pantograph in the scene")->required();
  app.add_option("--out", o->out_dir, "output directory (frf.csv, frf.png)")->required()->type_name("DIR");
  app.add_option("--fmin", o->fmin, "lowest measured frequency, Hz")->check(kFinite & CLI::Range(0.05, 200.0))->capture_default_str();
  app.add_option("--fmax", o->fmax, "highest measured frequency, Hz")->check(kFinite & CLI::Range(0.05, 200.0))->capture_default_str();
  app.add_option("--points", o->points, "measured frequencies (log spaced)")->check(CLI::Range(1, 400))->capture_default_str();
  app.add_option("--dt", o->dt, "largest time step of the simulated rig, s (smaller if its stability limit asks)")
      ->check(kFinite & CLI::Range(1e-7, 1e-2))
      ->capture_default_str();
  app.add_option("--max-steps", o->max_steps, "refuse a measurement that would take more rig steps than this")
      ->check(kFinite & CLI::Range(1.0, 1e12))
      ->capture_default_str();
  app.add_option("--force-share", o->share, "dynamic contact force amplitude as a share of the static uplift")
      ->check(kFinite & CLI::Range(0.01, 0.9))
      ->capture_default_str();
  app.add_option("--set", o->overrides, "override a scene field (as simulate_pass --set)")->type_name("KEY=VALUE")->take_all();
  app.add_flag("--no-plot", o->no_plot, "write the CSV only");
  try {
    app.parse(argc, argv);
    if (o->fmax < o->fmin) throw CLI::ValidationError("--fmax", "must be >= --fmin (" + fmt(o->fmin) + ")");
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return -1;
}

// The index of the pantograph --pantograph names, a lumped one with an uplift; -1 with the reason
// on stderr.
int rig_pantograph(const Scene& scene, const std::string& name) {
  int pi = -1;
  std::string names;
  for (std::size_t i = 0; i < scene.pantographs.size(); ++i) {
    names += (i ? ", " : "") + scene.pantographs[i].name;
    if (scene.pantographs[i].name == name) pi = static_cast<int>(i);
  }
  if (pi < 0) {
    std::cerr << "pantograph_frf: --pantograph '" << name << "' is not in the scene; allowed: " << names << "\n";
    return -1;
  }
  const PantographSpec& ps = scene.pantographs[pi];
  if (ps.moving_force || ps.external) {
    std::cerr << "pantograph_frf: --pantograph '" << name << "' is a " << (ps.external ? "external" : "moving_force")
              << " pantograph: it has no model masses; allowed: a lumped pantograph\n";
    return -1;
  }
  if (!(ps.static_uplift > 0.0)) {
    std::cerr << "pantograph_frf: pantograph '" << name << "' has static_uplift " << ps.static_uplift
              << " N; the rig needs > 0 N to keep the head on the wire\n";
    return -1;
  }
  return pi;
}

// frf.csv: the analytic and the measured response at each frequency; returns the largest
// |measured/analytic - 1| of the receptance.
double write_frf(const std::string& path, const std::vector<FrfPoint>& model, const std::vector<FrfPoint>& measured) {
  std::ostringstream out;
  out.precision(10);
  out << "frequency_hz,analytic_receptance_re_m_per_n,analytic_receptance_im_m_per_n,analytic_apparent_mass_kg,"
         "analytic_apparent_mass_phase_deg,measured_receptance_re_m_per_n,measured_receptance_im_m_per_n,"
         "measured_apparent_mass_kg,measured_apparent_mass_phase_deg,drive_amplitude_mm,settle_time_s\n";
  double worst = 0.0;
  for (std::size_t k = 0; k < model.size(); ++k) {
    const FrfPoint &a = model[k], &b = measured[k];
    out << a.frequency << "," << a.receptance.real() << "," << a.receptance.imag() << "," << std::abs(a.apparent_mass)
        << "," << deg(a.apparent_mass) << "," << b.receptance.real() << "," << b.receptance.imag() << ","
        << std::abs(b.apparent_mass) << "," << deg(b.apparent_mass) << "," << b.drive_amplitude * 1e3 << ","
        << b.settle_time << "\n";
    worst = std::max(worst, std::abs(b.receptance / a.receptance - 1.0));
  }
  write_file_atomically(path, out.str());
  return worst;
}

// frf_model.csv: the model's curve on a fine grid (0.02 Hz up to fmax) for the plot's lines.
void write_model_curve(const std::string& path, const Model& rig, double fmax) {
  std::vector<double> fine;
  for (double f = 0.02; f <= fmax + 1e-9; f += 0.02) fine.push_back(f);
  std::ostringstream curve;
  curve.precision(10);
  curve << "frequency_hz,receptance_re_m_per_n,receptance_im_m_per_n,apparent_mass_kg,apparent_mass_phase_deg\n";
  for (const FrfPoint& a : analytic_frf(rig, 0, fine))
    curve << a.frequency << "," << a.receptance.real() << "," << a.receptance.imag() << "," << std::abs(a.apparent_mass)
          << "," << deg(a.apparent_mass) << "\n";
  write_file_atomically(path, curve.str());
}

// Measures pantograph `pi` of `scene` on the rig and writes the files; returns the exit code.
// Throws SceneError or OutputError.
int measure(const FrfOptions& o, const Scene& scene, int pi) {
  make_directories(o.out_dir);
  DirectoryLock lock(o.out_dir);
  const std::string csv_path = o.out_dir + "/frf.csv", png_path = o.out_dir + "/frf.png";
  const std::string model_path = o.out_dir + "/frf_model.csv";
  check_writable(csv_path);
  check_writable(model_path);
  // The rig at the scene's automatic step, or --dt if smaller.
  Model rig = build_model(frf_rig_scene(scene, pi, 0.0));
  if (rig.dt > o.dt) rig = build_model(frf_rig_scene(scene, pi, o.dt));
  std::vector<double> freqs;
  for (int i = 0; i < o.points; ++i)
    freqs.push_back(o.points == 1 ? o.fmin : o.fmin * std::pow(o.fmax / o.fmin, static_cast<double>(i) / (o.points - 1)));
  FrfMeasurement how;
  how.dt = rig.dt;
  how.force_share = o.share;
  // Known before running: the steps grow as 1/dt, and a tiny --dt runs for hours without a word.
  const long long steps = frf_steps(rig, freqs, how);
  if (static_cast<double>(steps) > o.max_steps) {
    const double smallest = rig.dt * static_cast<double>(steps) / o.max_steps;
    std::cerr << "pantograph_frf: --dt " << o.dt << " s: the rig would take " << static_cast<double>(steps)
              << " steps for these " << freqs.size() << " frequencies, more than --max-steps " << o.max_steps
              << "; allowed: --dt >= " << smallest
              << " s here (or fewer --points, a higher --fmin, or a larger --max-steps)\n";
    return 2;
  }
  // A line per tenth of a long run (several million steps): seconds to minutes each.
  int shown = 0;
  if (steps > 20000000LL)
    how.progress = [&shown](long long done, long long total) {
      const int tenth = static_cast<int>(10 * done / std::max(1LL, total));
      if (tenth > shown) {
        shown = tenth;
        std::cerr << "pantograph_frf: " << 10 * tenth << " % of " << static_cast<double>(total) << " rig steps\n";
      }
    };
  const double worst = write_frf(csv_path, analytic_frf(rig, 0, freqs), measured_frf(rig, freqs, how));
  write_model_curve(model_path, rig, o.fmax);
  std::cerr << "pantograph_frf: " << freqs.size() << " frequencies " << o.fmin << "-" << o.fmax << " Hz, rig dt " << rig.dt
            << " s, slowest free decay " << slowest_decay_rate(rig, 0) << " 1/s; largest |measured/analytic - 1| "
            << worst << "; wrote " << csv_path << "\n";
  if (o.no_plot) return 0;
  std::string why;
  if (run_plot(csv_path, png_path, scene.name + ": pantograph " + o.name, &why) != 0) {
    std::cerr << "pantograph_frf: the plot failed" << (why.empty() ? "" : ": " + why) << " (the CSV is written)\n";
    return 3;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  FrfOptions o;
  if (const int rc = parse_options(argc, argv, &o); rc >= 0) return rc;
  try {
    const Scene scene = load_scene_file(o.scene_path, o.overrides);
    const int pi = rig_pantograph(scene, o.name);
    return pi < 0 ? 2 : measure(o, scene, pi);
  } catch (const SceneError& e) {
    std::cerr << "pantograph_frf: " << e.what() << "\n";
    return 2;
  } catch (const OutputError& e) {
    std::cerr << "pantograph_frf: " << e.what() << "\n";
    return 2;
  }
}
