// catenary_sim_hil_udp: hardware in the loop over UDP, without ROS. The catenary of a scene whose
// pantograph is `type: external` against a rig controller that exchanges the fixed packets of
// include/catenary_sim/hil/udp_packets.h (docs/hil.md, "UDP"). The loop is the ROS node's
// (hil::HilLoop): held or extrapolated measurement, the safe hold after the timeout.
//
//   catenary_sim_hil_udp --scene config/reference_55m_hil.yaml --port 47800 --report hil.json
//   udp_rig_client --pantograph-scene config/reference_55m.yaml --simulator 127.0.0.1:47800
#include <CLI/CLI.hpp>

#include <csignal>
#include <cstdlib>
#include <cstdio>
#include <exception>
#include <memory>
#include <optional>

#include <nlohmann/json.hpp>

#include "catenary_sim/core/output/output_files.hpp"
#include "catenary_sim/hil/loop.hpp"
#include "catenary_sim/hil/realtime.hpp"
#include "catenary_sim/hil/report.hpp"
#include "catenary_sim/hil/udp_loop.hpp"
#include "cli_checks.hpp"

using namespace catenary_sim;

namespace {

// --rate by the loop's own check (hil::loop_rate_error), in the words of the ROS node's ~hil/rate
// (a non-number is kFinite's to refuse).
const CLI::Validator kLoopRate(
    [](std::string& text) -> std::string {
      char* end = nullptr;
      const double rate = std::strtod(text.c_str(), &end);
      if (text.empty() || *end != '\0') return std::string();
      return hil::loop_rate_error(rate, "--rate");
    },
    "HZ");

hil::UdpLoopSkin* g_skin = nullptr;
extern "C" void on_signal(int) {
  if (g_skin) g_skin->stop();  // (an atomic store: async-signal-safe)
}


// The command line.
struct UdpOptions {
  std::string scene_file, rig, report_file, stats_file, at_end = "exit", allow;
  std::optional<std::string> cpus;  // (given empty: refused by parse_cpu_list)
  std::optional<double> speed_kmh;
  hil::LoopOptions lo;
  hil::UdpLoopOptions uo;
  hil::RealtimeOptions rt;
  double duration = 0.0;
};

// Parses argv into *o; returns -1 to go on, else the exit code (--help: 0; bad flags: CLI11's, 2
// for a bad --rig, --allow or --cpus).
int parse_options(int argc, char** argv, UdpOptions* o) {
  CLI::App app{"Hardware in the loop over UDP (no ROS): the catenary against a rig's measured contact force."};
  hil::LoopOptions& lo = o->lo;
  lo.who = "catenary_sim_hil_udp";
  lo.input = "UDP measurement";
  lo.command_line = true;
  app.add_option("--scene", o->scene_file, "scene YAML with at least one `type: external` pantograph")->required()->type_name("FILE");
  app.add_option("--speed-kmh", o->speed_kmh, "train speed, km/h (default: the scene's)")->check(kFinite & CLI::Range(0.0, 3.6 * kMaxTrainSpeed));
  app.add_option("--rate", lo.rate, "loop rate, Hz")->check(kFinite & kLoopRate)->capture_default_str();
  app.add_option("--timeout", lo.timeout, "s without a valid measurement before the safe hold (>= 2 periods)")
      ->check(kFinite & CLI::Range(0.0002, 10.0))->capture_default_str();
  app.add_flag("--extrapolate", lo.extrapolate, "extrapolate the last two measurements instead of holding the newest");
  app.add_option("--hold-ramp", lo.hold_ramp, "s, force ramp to the static force in the safe hold")
      ->check(kFinite & CLI::Range(0.0, 60.0))->capture_default_str();
  app.add_option("--hold-deceleration", lo.hold_deceleration, "m/s^2, the train stops at this rate in the safe hold (0: at once)")
      ->check(kFinite & CLI::Range(0.0, Simulation::kMaxAcceleration))->capture_default_str();
  app.add_option("--start-delay", lo.start_delay, "s in which measurements are ignored")->check(kFinite & CLI::Range(0.0, 60.0));
  app.add_option("--delay-compensation", lo.delay_compensation,
                 "s: send the contact point predicted this far ahead (the known loop delay)")
      ->check(kFinite & CLI::Range(0.0, 0.1))->capture_default_str();
  app.add_option("--at-end", o->at_end, "at the end of the pass: exit, stop (hold the last state) or loop")
      ->check(CLI::IsMember({"exit", "stop", "loop"}))->capture_default_str();
  app.add_option("--bind", o->uo.bind_address, "local IPv4 address to receive on")->capture_default_str();
  app.add_option("--port", o->uo.port, "local UDP port to receive on")->check(CLI::Range(0, 65535))->capture_default_str();
  app.add_option("--rig", o->rig, "HOST:PORT of the rig (default: the source of its newest valid measurement)");
  app.add_option("--allow", o->allow, "senders that may be the rig: IPv4 addresses, each with an optional :PORT, "
                 "separated by commas (default: any; the rig is the first valid sender)");
  app.add_flag("--same-clock", o->uo.same_clock, "the rig's send_time_ns is this machine's CLOCK_MONOTONIC (transport measured)");
  app.add_option("--report", o->report_file, "JSON at exit: latency, jitter, overruns, packets, coupling energy")->type_name("FILE");
  app.add_option("--stats", o->stats_file, "the pass statistics JSON (as simulate_pass)")->type_name("FILE");
  app.add_flag("--lock-memory", o->rt.lock_memory, "mlockall: no page faults in the loop");
  app.add_option("--fifo-priority", o->rt.fifo_priority, "SCHED_FIFO priority of the loop thread (0: normal)")->check(CLI::Range(0, 99));
  app.add_option("--cpus", o->cpus, "CPUs of the loop thread, e.g. 3 or 2,3 (isolcpus)");
  app.add_option("--duration", o->duration, "s (wall) after which the loop stops (0: until the pass ends or a signal)")
      ->check(kFinite & CLI::Range(0.0, 1e6));
  CLI11_PARSE(app, argc, argv);
  try {
    if (!o->rig.empty()) std::tie(o->uo.rig_address, o->uo.rig_port) = hil::parse_host_port(o->rig, "--rig");
    o->uo.allow = hil::parse_allow_list(o->allow, "--allow");
    if (o->cpus) o->rt.cpus = hil::parse_cpu_list(*o->cpus, "--cpus");
  } catch (const hil::HilError& e) {
    std::fprintf(stderr, "catenary_sim_hil_udp: %s\n", e.what());
    return 2;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "catenary_sim_hil_udp: %s\n", e.what());
    return 2;
  }
  lo.at_end = o->at_end == "loop" ? hil::EndAction::kLoop : o->at_end == "stop" ? hil::EndAction::kStop : hil::EndAction::kExit;
  return -1;
}

// What the loop did, on stdout; the statistics (--stats) and the report (--report) written. False
// when --stats was asked for a pass that gave none (stopped at a dewirement before the analysis
// section): the file is missing.
bool finish(const UdpOptions& o, hil::HilLoop& loop, hil::UdpLoopSkin& skin, double start) {
  std::printf("catenary_sim_hil_udp: %s\n", hil::loop_summary(loop).c_str());
  const auto& seq = skin.sequence();
  std::printf("catenary_sim_hil_udp: packets: %llu received, %llu lost, %llu reordered, %llu duplicated, %llu from "
              "other senders, %llu refused (--allow), %llu sent\n",
              static_cast<unsigned long long>(seq.received()), static_cast<unsigned long long>(seq.lost()),
              static_cast<unsigned long long>(seq.reordered()), static_cast<unsigned long long>(seq.duplicates()),
              static_cast<unsigned long long>(skin.foreign()), static_cast<unsigned long long>(skin.refused()),
              static_cast<unsigned long long>(skin.sent()));
  const hil::CouplingEnergy& en = loop.energy();
  std::printf("catenary_sim_hil_udp: coupling: %.4g J of work on the line at the interface, %.4g J of it added by "
              "the loop delay (%lld of %lld periods with the answered contact point known)\n",
              en.interface_j, en.delay_j, static_cast<long long>(en.known), static_cast<long long>(en.periods));
  State end_state;
  bool stats_missing = false;
  if (std::unique_ptr<PassRecorder> rec = skin.take_finished(&end_state)) {
    const std::vector<PantographStatistics> st = rec->statistics(loop.model());
    std::string why;
    const std::string text = hil::pass_stats_json(loop.model(), end_state, st,
                                                  RunInfo{hil::steady_now() - start, -1.0, loop.counters().overruns}, &why);
    if (text.empty()) {
      std::fprintf(stderr, "catenary_sim_hil_udp: %s\n", why.c_str());
      stats_missing = !o.stats_file.empty();
    } else {
      for (const PantographStatistics& s : st)
        std::printf("catenary_sim_hil_udp: %s: mean %.1f N, std %.1f N, max %.1f N, min %.1f N, contact loss %.2f %%\n",
                    s.name.c_str(), s.filtered.mean, s.filtered.std_dev, s.filtered.max, s.filtered.min,
                    s.contact_loss_percent);
      if (!o.stats_file.empty()) write_file_atomically(o.stats_file, text);
    }
  }
  if (!o.report_file.empty()) {
    nlohmann::ordered_json j = hil::loop_report(loop);
    skin.add_report(j);
    write_file_atomically(o.report_file, j.dump(2) + "\n");
  }
  return !stats_missing;
}

// The loop run to its end; returns its exit code. Throws HilError, SceneError, OutputError.
int run_loop(const UdpOptions& o) {
  if (!o.report_file.empty()) check_writable(o.report_file);
  if (!o.stats_file.empty()) check_writable(o.stats_file);
  if (const std::string e = hil::check_realtime(o.rt); !e.empty()) throw hil::HilError(e);
  Scene scene = load_scene_file(o.scene_file);
  if (o.speed_kmh) scene.train_speed = *o.speed_kmh / 3.6;
  hil::HilLoop loop(scene, o.lo, "--rate", "--scene " + o.scene_file);
  hil::UdpLoopOptions uo = o.uo;
  uo.scene_name = "--scene " + o.scene_file;
  hil::UdpLoopSkin skin(loop, uo);
  const double start = hil::steady_now();
  const double duration = o.duration;
  if (duration > 0.0) skin.set_running([start, duration] { return hil::steady_now() - start < duration; });
  g_skin = &skin;
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  if (const std::string e = hil::apply_realtime(o.rt); !e.empty()) throw hil::HilError(e);
  std::fprintf(stderr, "[INFO] catenary_sim_hil_udp: %s: loop %g Hz = %d step(s) of %.6g ms; listening on UDP %s:%d%s\n",
               scene.name.c_str(), o.lo.rate, loop.timing().steps_per_period, loop.model().dt * 1e3,
               o.uo.bind_address.c_str(), skin.port(), o.rig.empty() ? "" : (", sending to " + o.rig).c_str());
  const int rc = loop.run();
  g_skin = nullptr;
  skin.finish();  // the rig is told that the pass ended (or that the simulator stops)
  const bool stats_ok = finish(o, loop, skin, start);
  return rc == 0 && !stats_ok ? 1 : rc;
}

}  // namespace

int main(int argc, char** argv) {
  UdpOptions o;
  if (const int rc = parse_options(argc, argv, &o); rc >= 0) return rc;
  try {
    return run_loop(o);
  } catch (const hil::HilError& e) {
    std::fprintf(stderr, "catenary_sim_hil_udp: %s\n", e.what());
    return 2;
  } catch (const SceneError& e) {
    std::fprintf(stderr, "catenary_sim_hil_udp: --scene %s: %s\n", o.scene_file.c_str(), e.what());
    return 2;
  } catch (const OutputError& e) {
    std::fprintf(stderr, "catenary_sim_hil_udp: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "catenary_sim_hil_udp: %s\n", e.what());
    return 2;
  }
}
