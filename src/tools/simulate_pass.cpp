// simulate_pass: one offline pass of a scene, no ROS master needed.
//   simulate_pass --scene FILE [--speed KMH] [--set key=value ...] --out DIR [--report]
// Prints a summary, writes DIR/stats.json, DIR/timeseries.csv and the measurement files
// (force_processed.csv, contact_losses.csv, droppers.csv, dropper_rainflow.csv, psd.csv, and
// dropper_series.csv when output.dropper_series; lateral.csv, lateral_histogram.csv, blow_off.csv,
// pull_off.csv and dewirements.csv on a 3-D line), each whole or not at all (temporary file +
// rename), with DIR locked against a second run writing into it. --report then runs
// scripts/pass_report on DIR (report.html and its PNGs).
#include <sys/stat.h>
#include <unistd.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <memory>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "catenary_sim/core/output/lateral_statistics.hpp"
#include "catenary_sim/core/output/output_files.hpp"
#include "catenary_sim/core/output/pass_files.hpp"
#include "catenary_sim/tools/report_launcher.hpp"
#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "cli_checks.hpp"
#include "pass_bag_writer.hpp"

using namespace catenary_sim;

namespace {

// Exit codes: 0 done, 2 bad input or failed write, 3 diverged; a bad command line exits with
// CLI11's own non-zero codes (and --help with 0).
constexpr int kBadInput = 2, kDiverged = 3;

// A pass of more steps is refused unless --max-steps raises the bound: at the accurate preset's
// ~0.1 ms per step of the 4405-DOF reference scene (BENCHMARKS.md) 2e7 steps are about half an
// hour; a speed of 0.001 km/h would need billions and never end.
constexpr double kDefaultMaxSteps = 2e7;

// A progress line on a terminal (stderr), redrawn at most twice a second: share done, simulated
// time, the real-time factor so far and the estimated end. Silent when stderr is not a terminal.
class Progress {
 public:
  Progress(double total_steps, bool enabled)
      : total_(total_steps), enabled_(enabled && ::isatty(STDERR_FILENO)), start_(Clock::now()), last_(start_) {}
  void update(std::int64_t steps, double sim_time) {
    if (!enabled_ || (steps & 255) != 0) return;
    const auto now = Clock::now();
    if (std::chrono::duration<double>(now - last_).count() < 0.5) return;
    last_ = now;
    const double wall = std::chrono::duration<double>(now - start_).count();
    const double share = std::min(1.0, steps / total_);
    const double left = share > 0.0 ? wall * (1.0 - share) / share : 0.0;
    const int width = 30, filled = static_cast<int>(share * width);
    std::fprintf(stderr, "\r[%s%s] %5.1f %%  t = %.2f s  %.1fx real time  about %.0f s left   ",
                 std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(), 100.0 * share, sim_time,
                 wall > 0.0 ? sim_time / wall : 0.0, left);
    drawn_ = true;
  }
  void done() {
    if (drawn_) std::fprintf(stderr, "\r%s\r", std::string(100, ' ').c_str());
  }

 private:
  using Clock = std::chrono::steady_clock;
  double total_;
  bool enabled_, drawn_ = false;
  Clock::time_point start_, last_;
};

bool all_finite(const std::vector<PantographStatistics>& stats) {
  for (const PantographStatistics& s : stats)
    for (double v : {s.filtered.mean, s.filtered.std_dev, s.filtered.max, s.filtered.min, s.unfiltered.mean})
      if (!std::isfinite(v)) return false;
  return true;
}

// The command line.
struct Options {
  std::string scene_path, out_dir, bag_path;
  std::vector<std::string> overrides;
  double speed_kmh = std::nan("");
  double max_steps = kDefaultMaxSteps;
  bool quiet = false, no_progress = false, report = false;
  double bag_rate = 200.0;
};

// Parses argv into *o; returns -1 to go on, else the exit code (--help: 0; bad flags and values:
// CLI11's message and a non-zero code).
int parse_options(int argc, char** argv, Options* o) {
  CLI::App app{"One offline pantograph pass over a scene (no ROS master needed). Writes DIR/stats.json and "
               "DIR/timeseries.csv, each whole or not at all.",
               "simulate_pass"};
  app.add_option("--scene", o->scene_path, "scene YAML (docs/scene_reference.md, e.g. config/reference_55m.yaml)")
      ->required()
      ->type_name("FILE");
  app.add_option("--out", o->out_dir, "output directory for stats.json and timeseries.csv (created)")
      ->required()
      ->type_name("DIR");
  app.add_option("--speed", o->speed_kmh, "train speed in km/h, overrides train.speed / train.speed_kmh")
      ->check(kFinite & CLI::Range(0.0, 3.6 * kMaxTrainSpeed))
      ->type_name("KMH");
  app.add_option("--set", o->overrides, "override a scene field, e.g. --set numerics.element_length=0.125 (null removes it)")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false)
      ->take_all();
  app.add_option("--bag", o->bag_path, "also write the node's topics into a rosbag (simulation-time stamps)")
      ->type_name("FILE");
  app.add_option("--bag-rate", o->bag_rate,
                 "rate of /contact_force, /pantograph_state and /tf in the bag (Hz; 0: every step)")
      ->check(kFinite & CLI::Range(0.0, 1e6))
      ->capture_default_str()
      ->type_name("HZ");
  app.add_option("--max-steps", o->max_steps, "refuse a pass of more steps than this (a bound against runs that never end)")
      ->check(kFinite & CLI::Range(1.0, 1e12))
      ->capture_default_str()
      ->type_name("N");
  app.add_flag("--report", o->report,
               "after the pass, write DIR/report.html and its PNGs with scripts/pass_report (needs python3-matplotlib)");
  app.add_flag("--quiet", o->quiet, "print only errors");
  app.add_flag("--no-progress", o->no_progress, "no progress line (it is drawn only on a terminal anyway)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return -1;
}

// The scene with the command line's speed and overrides, checked for an offline pass; throws
// SceneError naming the field.
Scene load_pass_scene(const Options& o) {
  Scene scene = load_scene_file(o.scene_path, o.overrides);
  if (!std::isnan(o.speed_kmh)) {
    // The scene's own limit (below the contact wire's wave speed), named as the flag.
    if (const TrainSpeedLimit limit = train_speed_limit(scene); !limit.allows(o.speed_kmh / 3.6)) {
      std::ostringstream s;
      s.precision(10);
      s << "--speed " << o.speed_kmh << " km/h: allowed " << limit.text();
      throw SceneError(s.str());
    }
    scene.train_speed = o.speed_kmh / 3.6;
    validate(scene);
  }
  // An external pantograph's force is measured on a real pantograph; offline nothing measures
  // it and it would stay a constant force.
  for (std::size_t i = 0; i < scene.pantographs.size(); ++i)
    if (scene.pantographs[i].external)
      throw SceneError("scene field 'pantographs[" + std::to_string(i) + "].type' = 'external': needs a live rig that "
                       "measures the contact force (catenary_sim_hil_udp, the HIL node, or Python's "
                       "set_external_force); an offline pass takes lumped or moving_force");
  // The core steps a line without pantographs (its free vibration; elasticity_curve loads the line
  // statically); a pass has nothing to report without one.
  if (scene.pantographs.empty())
    throw SceneError("scene field 'pantographs' = (none): an offline pass needs at least one pantograph (a list of "
                     "pantographs[i] with type lumped or moving_force; the line's static elasticity alone: "
                     "elasticity_curve)");
  if (!(scene.train_speed > 0.0))
    throw SceneError("scene field 'train.speed_kmh' = 0 (or not given): an offline pass needs a train speed > 0 (give "
                     "train.speed_kmh in the scene or --speed; the live node accepts 0 and waits for a speed command)");
  return scene;
}

// Builds the pass's simulation into *sim; returns -1 to go on, else the exit code (the reason on
// stderr).
int build_pass(const Options& o, Scene* scene, std::unique_ptr<Simulation>* sim) {
  try {
    *scene = load_pass_scene(o);
    *sim = std::make_unique<Simulation>(*scene);
  } catch (const SceneError& e) {
    std::cerr << "simulate_pass: " << e.what() << "\n";
    return kBadInput;
  } catch (const std::bad_alloc&) {
    std::cerr << "simulate_pass: out of memory while building the model of '" << o.scene_path
              << "'; use a longer numerics.element_length or fewer spans\n";
    return kBadInput;
  }
  const Model& m = (*sim)->model();
  const double steps_needed = pass_step_count(m);
  if (!(steps_needed <= o.max_steps)) {
    std::ostringstream s;
    s.precision(3);
    s << "simulate_pass: the pass would take " << steps_needed << " steps (" << pass_distance(m)
      << " m at " << scene->train_speed * 3.6 << " km/h with dt " << m.dt << " s), more than --max-steps "
      << o.max_steps << "; raise --max-steps if that is meant, or check train.speed_kmh, the line length and "
      << "the masses that set dt";
    const std::string note = short_element_note(m);
    if (!note.empty()) s << "; " << note;
    std::cerr << s.str() << "\n";
    return kBadInput;
  }
  return -1;
}

// The output directory: created, locked against a second run, and checked writable before the
// pass (a full or read-only target is found now, not after the pass). *bag_target: the bag's path
// with its links followed. Returns -1 to go on, else the exit code.
int prepare_outputs(const Options& o, const Model& m, std::unique_ptr<DirectoryLock>* lock, std::string* bag_target,
                    std::vector<std::string>* made) {
  try {
    *made = make_directories(o.out_dir);
    *lock = std::make_unique<DirectoryLock>(o.out_dir);
    check_pass_files_writable(o.out_dir, m);
    if (!o.bag_path.empty()) {
      // rosbag seeks back to write its header and index: it needs a regular file (a link to one
      // is kept and its target written).
      const OutputTarget target = output_target(o.bag_path);
      *bag_target = target.path;
      if (target.stream)
        throw OutputError("--bag '" + o.bag_path + "': a rosbag needs a regular file (it seeks back to write its index), "
                          "not a FIFO or device");
      check_writable(o.bag_path);
    }
  } catch (const OutputError& e) {
    std::cerr << "simulate_pass: " << e.what() << "\n";
    return kBadInput;
  }
  return -1;
}

void print_scene(const Scene& scene, const Model& m) {
  if (m.endless)
    std::cout << "scene " << scene.name << ": endless line of " << m.endless_span << " m spans (a block of "
              << m.scene.spans.size() << " moves along under the train), ";
  else
    std::cout << "scene " << scene.name << ": " << scene.spans.size() << " spans, " << m.line_length << " m, ";
  // The centred damping step named where the scene takes it: its dt is the undamped limit, above the half-step's.
  std::cout << m.n_dof << " DOFs, dt " << m.dt * 1e3 << " ms (stability limit " << m.dt_critical * 1e3 << " ms"
            << (scene.numerics.damping == DampingStep::kCentred ? ", centred damping" : "") << "), speed "
            << scene.train_speed * 3.6 << " km/h" << std::endl;
}

// The pass stepped to its end, every state into the recorders (and the bag).
struct PassRun {
  StepStatus status = StepStatus::kOk;
  std::unique_ptr<PassBagWriter> bag;
  std::string bag_tmp;  // the bag under its temporary name until the pass's files are written
  double wall_s = 0.0;
};

// Runs the pass into *run; returns -1 to go on, else the exit code (the reason on stderr, no half
// bag left).
int run_pass(const Options& o, Simulation& sim, const std::string& bag_target,
             PassRecorder& recorder, LateralRecorder& lateral, PassRun* run) {
  const Model& m = sim.model();
  const auto t0 = std::chrono::steady_clock::now();
  // The bag is written under a temporary name and renamed when complete (rosbag writes its index
  // at close), so a failed pass never leaves a half bag under the asked name.
  run->bag_tmp = o.bag_path.empty() ? "" : bag_target + ".partial";
  try {
    recorder.record(m, sim.state());
    lateral.record(m, sim.state());
    if (!o.bag_path.empty()) {
      run->bag = open_pass_bag(run->bag_tmp, o.bag_rate);
      run->bag->write_scene(o.scene_path, o.overrides);
      run->bag->write(m, sim.state(), &recorder);
    }
    Progress progress(pass_step_count(m), !o.quiet && !o.no_progress);
    while ((run->status = sim.step()) == StepStatus::kOk) {
      recorder.record(m, sim.state());
      lateral.record(m, sim.state());
      if (run->bag) run->bag->write(m, sim.state(), &recorder);
      progress.update(sim.state().steps, sim.state().time);
    }
    progress.done();
    if (run->bag) run->bag->close();
  } catch (const std::exception& e) {
    std::cerr << "simulate_pass: " << (o.bag_path.empty() ? "" : "--bag '" + o.bag_path + "': ") << e.what() << "\n";
    if (!run->bag_tmp.empty()) std::remove(run->bag_tmp.c_str());
    return kBadInput;
  }
  run->wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (run->status == StepStatus::kDiverged) {
    std::cerr << "simulate_pass: " << sim.status_message() << "\n";
    if (!run->bag_tmp.empty()) std::remove(run->bag_tmp.c_str());
    return kDiverged;
  }
  if (run->status == StepStatus::kDewired) {
    // The pass ends here as the scene asks (pantograph_head.on_dewirement: stop); what it ran is written.
    recorder.record(m, sim.state());
    lateral.record(m, sim.state());
    std::cerr << "simulate_pass: " << sim.status_message() << "\n";
  }
  return -1;
}

void print_pantograph(const PantographStatistics& s) {
  std::cout << std::setprecision(1) << "  " << s.name << ": mean " << s.filtered.mean << " N, std "
            << s.filtered.std_dev << " N, max " << s.filtered.max << " N, min " << s.filtered.min
            << " N, stat max " << s.filtered.stat_max << " N, stat min " << s.filtered.stat_min
            << " N, contact loss " << std::setprecision(2) << s.contact_loss_percent << " %, max uplift at steady arm ";
  if (std::isnan(s.max_uplift_at_support_m)) std::cout << "none (no steady arms)";
  else std::cout << std::setprecision(1) << s.max_uplift_at_support_m * 1e3 << " mm";
  std::cout << "\n"
            << std::setprecision(1) << "      unfiltered: max " << s.unfiltered.max << " N, min " << s.unfiltered.min << " N, std "
            << s.unfiltered.std_dev << " N\n";
  if (s.target_mean) {
    const PantographStatistics::TargetMean& t = *s.target_mean;
    std::cout << std::setprecision(1) << "      target mean force Fm(" << 3.6 * t.speed_mps << " km/h) " << t.target
              << " N: mean " << std::showpos << t.difference << std::noshowpos << " N from it";
    if (t.tolerance) std::cout << ", " << (t.within ? "within" : "OUTSIDE") << " the tolerance of +-" << *t.tolerance << " N";
    std::cout << "\n";
  }
  if (s.wires.size() > 1)
    for (const WireContactStatistics& w : s.wires)
      std::cout << "      on " << w.wire << ": mean " << w.mean_force << " N, max " << w.max_force << " N, in contact "
                << w.contact_percent << " % of the time\n";
  std::cout << std::setprecision(2) << "      contact losses: " << s.loss_events_total << " (" << s.loss_events_per_km
            << " per km), longest " << s.longest_loss_s * 1e3 << " ms\n";
  // (No speed through the section where the pantograph is sampled there fewer than twice.)
  if (std::isnan(s.spectrum.span_passing_hz)) std::cout << "      spectrum: span passing unknown (too few samples in the analysis section)";
  else std::cout << "      spectrum: span passing " << s.spectrum.span_passing_hz << " Hz";
  std::cout << ", dropper passing ";
  if (std::isnan(s.spectrum.span_passing_hz)) std::cout << "unknown";
  else if (std::isnan(s.spectrum.dropper_passing_hz)) std::cout << "none (no droppers)";  // a trolley wire, a rail
  else std::cout << s.spectrum.dropper_passing_hz << " Hz";
  std::cout << "; peaks";
  for (const SpectralPeak& k : s.spectrum.peaks)
    std::cout << " " << k.frequency << " Hz (" << std::setprecision(1) << k.amplitude << " N)" << std::setprecision(2);
  std::cout << "\n";
  if (s.measured.available)
    std::cout << std::setprecision(1) << "      measuring pantograph (" << s.measured.bandwidth_hz << " Hz): mean "
              << s.measured.force.mean << " N, std " << s.measured.force.std_dev << " N, rms difference to the true "
              << "filtered force " << std::setprecision(2) << s.measured.rms_difference << " N\n";
}

void print_line(const Scene& scene, const LineStatistics& line) {
  for (const bool hangers : {false, true}) {  // (a compound line's hangers on a line of their own)
    double fmax = 0.0, slack = 0.0, rmax = 0.0;
    int count = 0;
    for (const DropperStatistics& d : line.droppers) {
      if (d.hanger != hangers) continue;
      ++count;
      fmax = std::max(fmax, d.max_force);
      slack = std::max(slack, d.slack_percent);
      rmax = std::max(rmax, d.max_range);
    }
    if (count == 0) continue;
    std::cout << std::setprecision(1) << (hangers ? "hangers (" : "droppers (") << count << " in the section): max force " << fmax
              << " N, most slack " << std::setprecision(2) << slack << " % of the time, largest rainflow range "
              << std::setprecision(1) << rmax << " N\n";
  }
  int exceeded = 0;
  for (const SteadyArmStatistics& a : line.steady_arms) exceeded += a.exceeded;
  if (scene.output.allowed_uplift)
    std::cout << "steady arms: " << exceeded << " of " << line.steady_arms.size() << " above the allowed uplift of "
              << *scene.output.allowed_uplift * 1e3 << " mm\n";
}

void print_lateral(const Scene& scene, const Model& m, const LateralStatistics& ls) {
  const std::string coupling = lateral_coupling(m);  // "how: why"; the summary gives the how
  std::cout << std::setprecision(3) << "3-D line (lateral plane coupled " << coupling.substr(0, coupling.find(':'))
            << "): working width +-" << 0.5 * scene.pantograph_head.working_width << " m\n";
  for (const LateralContactStatistics& c : ls.contacts)
    std::cout << "  " << c.pantograph << " contact point across the strip: mean " << c.mean << " m, range " << c.min
              << " .. " << c.max << " m, sweep speed mean " << c.sweep_mean << " m/s (max " << c.sweep_max
              << " m/s), beyond the working width " << std::setprecision(2) << c.outside_working_percent << " % of the time\n"
              << std::setprecision(3);
  double worst = 0.0, worst_static = 0.0;
  int exceeded = 0;
  for (const SpanBlowOff& b : ls.spans) {
    worst = std::max(worst, b.max_m);
    worst_static = std::max(worst_static, b.static_m);
    exceeded += b.exceeded;
  }
  std::cout << "  blow-off of the contact wire: static " << worst_static << " m, max " << worst << " m";
  if (scene.wind && scene.wind->blow_off_limit)
    std::cout << "; " << exceeded << " of " << ls.spans.size() << " spans above the limit of " << *scene.wind->blow_off_limit << " m";
  // The registrations' pull-off: the still line's, and under the mean wind where there is one.
  // (steady arms on a catenary, the suspension clamps on a rail, a bridle's middle on a trolley wire)
  double pull = 0.0, pull_wind = 0.0;
  for (const LateralSupport& s : m.lateral->supports)
    if (!s.anchor && (m.wires[s.wire].is_contact_wire || m.wires[s.wire].is_bridle)) {
      pull = std::max(pull, std::fabs(s.pull_off));
      pull_wind = std::max(pull_wind, std::fabs(s.pull_off_wind));
    }
  std::cout << "\n  largest pull-off at a registration " << std::setprecision(1) << pull << " N";
  if (m.lateral->windy) std::cout << " (" << pull_wind << " N in the mean wind)";
  std::cout << "; dewirements: " << ls.events_total << "\n";
}

// The summary on stdout: the pass, per pantograph its statistics, the line's.
void print_summary(const Options& o, const Scene& scene, const Model& m, const State& st, const PassRun& run,
                   const std::vector<PantographStatistics>& stats, const PassRecorder& recorder,
                   const LateralRecorder& lateral) {
  const double rtf = run.wall_s > 0.0 ? st.time / run.wall_s : std::nan("");
  std::cout << std::fixed << std::setprecision(2);
  std::cout << "pass: " << st.steps << " steps, " << st.time << " s simulated in " << run.wall_s << " s wall ("
            << std::setprecision(1) << rtf << "x real time)\n";
  double x0 = 0.0, x1 = 0.0;
  analysis_section(m, &x0, &x1);
  std::cout << "statistics over " << x0 << "-" << x1 << " m, contact force low-pass " << scene.output.filter_cutoff << " Hz:\n";
  for (const PantographStatistics& s : stats) print_pantograph(s);
  print_line(scene, recorder.line_statistics(m));
  if (m.lateral) print_lateral(scene, m, lateral.statistics(m, st));
  std::cout << "wrote " << o.out_dir << "/stats.json, " << o.out_dir << "/timeseries.csv and the measurement files in "
            << o.out_dir << "\n";
  if (run.bag) std::cout << "wrote " << run.bag->messages() << " messages to " << o.bag_path << "\n";
}

// --report: scripts/pass_report on the written directory; returns the exit code.
int draw_report(const Options& o) {
  std::cout.flush();  // the summary before the report's lines
  std::string why;
  const pid_t pid = start_pass_report(o.out_dir, "", o.quiet, &why);
  const int rc = pid < 0 ? -1 : pass_report_status(pid, true);
  if (rc == 0) return 0;
  std::cerr << "simulate_pass: --report: " << (rc < 0 ? why : "scripts/pass_report failed (exit " + std::to_string(rc) + ")")
            << "; the pass's files are written\n";
  return kBadInput;
}

}  // namespace

int main(int argc, char** argv) {
#ifdef __GLIBC__
  // The model's build allocates and frees many large temporaries (the statics' triplets and
  // matrices). By default glibc maps each above 128 KiB afresh and returns freed heap to the
  // system, so every one is faulted in page by page again: about half of building the accurate
  // reference model. Kept in the heap, freed memory is reused; the peak stays what it is, and
  // this process ends after one pass.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
  Options o;
  if (const int rc = parse_options(argc, argv, &o); rc >= 0) return rc;
  Scene scene;
  std::unique_ptr<Simulation> sim;
  const auto t_build = std::chrono::steady_clock::now();
  if (const int rc = build_pass(o, &scene, &sim); rc >= 0) return rc;
  const Model& m = sim->model();
  std::unique_ptr<DirectoryLock> lock;
  std::string bag_target;
  std::vector<std::string> made;  // the output directories this run created
  if (const int rc = prepare_outputs(o, m, &lock, &bag_target, &made); rc >= 0) return rc;
  // A pass that ends writing nothing (it diverged) takes back the lock file and directories it made.
  auto written_nothing = [&](int rc) {
    lock->remove_if_made();
    lock.reset();
    remove_made_directories(made);
    return rc;
  };

  PassRecorder recorder(m, scene.output.sample_rate);
  LateralRecorder lateral(m, scene.output.sample_rate);  // records nothing on a 2-D line
  if (!o.quiet) print_scene(scene, m);
  for (const std::string& w : m.warnings) std::cerr << "simulate_pass: warning: " << w << "\n";
  const double build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_build).count();
  PassRun run;
  if (const int rc = run_pass(o, *sim, bag_target, recorder, lateral, &run); rc >= 0) return written_nothing(rc);
  const State& st = sim->state();
  const std::vector<PantographStatistics> stats = recorder.statistics(m);
  if (!all_finite(stats)) {
    if (run.status == StepStatus::kDewired)
      std::cerr << "simulate_pass: the pass stopped at the dewirement before it crossed the analysis section; nothing written\n";
    // Guarded by the scene checks (every pantograph crosses the analysis section); never written as null.
    std::cerr << "simulate_pass: the pass gave no statistics over the analysis section (output.analysis_spans); "
                 "nothing written\n";
    if (!run.bag_tmp.empty()) std::remove(run.bag_tmp.c_str());
    return written_nothing(kBadInput);
  }
  try {
    RunInfo info;
    info.wall_time_s = run.wall_s;
    info.build_time_s = build_s;
    write_pass_files(o.out_dir, m, st, recorder, info, &lateral, run.status == StepStatus::kDewired, &stats);
    if (!run.bag_tmp.empty() && std::rename(run.bag_tmp.c_str(), bag_target.c_str()) != 0)
      throw OutputError("cannot write '" + o.bag_path + "': rename failed");
  } catch (const OutputError& e) {
    std::cerr << "simulate_pass: " << e.what() << "\n";
    if (!run.bag_tmp.empty()) std::remove(run.bag_tmp.c_str());
    return kBadInput;
  }
  if (!o.quiet) print_summary(o, scene, m, st, run, stats, recorder, lateral);
  return o.report ? draw_report(o) : 0;
}
