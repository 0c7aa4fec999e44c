// udp_rig_client: an example rig controller for catenary_sim_hil_udp, in plain C++ without ROS.
// It speaks the packets of include/catenary_sim/hil/udp_packets.h; its "rig" is simulated (the
// lumped pantograph of a scene, hil::RigPantograph, as virtual_rig): a real controller replaces
// the pantograph by its actuator (drive to `height` with `path_velocity` as feed-forward) and its
// load cell (send the measured total force with the `step` of the newest contact point).
//
//   udp_rig_client --pantograph-scene config/reference_55m.yaml --simulator 127.0.0.1:47800
//
// It stops when the simulator sends the end (csim_udp_end), or after --timeout without a contact
// point (the simulator died), or when no contact point came within --connect-timeout.
#include <CLI/CLI.hpp>

#include <atomic>
#include <csignal>
#include <cstdio>

#include "catenary_sim/hil/udp_loop.hpp"
#include "cli_checks.hpp"

using namespace catenary_sim;

namespace {
std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop = true; }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"An example rig for catenary_sim_hil_udp: a simulated lumped pantograph over UDP (no ROS)."};
  std::string scene_file, simulator = "127.0.0.1:47800";
  hil::UdpRigOptions o;
  bool until_ended = true;
  app.add_option("--pantograph-scene", scene_file, "scene whose lumped pantographs stand for the external ones, in order")
      ->required()->type_name("FILE");
  app.add_option("--simulator", simulator, "HOST:PORT of catenary_sim_hil_udp")->capture_default_str();
  app.add_option("--port", o.port, "local UDP port (0: any)")->check(CLI::Range(0, 65535))->capture_default_str();
  app.add_option("--rate", o.rate, "the rig's loop, Hz (0: the simulator's rate)")
      ->check(kFinite & CLI::Range(0.0, 20000.0))->capture_default_str();
  app.add_flag("--hold{false},--extrapolate", o.extrapolate, "between contact points follow the path velocity (default) or hold");
  app.add_flag("!--keep-running", until_ended, "keep running after the simulator reports the end of a pass (a new pass may come)");
  app.add_option("--timeout", o.contact_timeout, "s without a contact point (once one came) after which the rig stops (0: never)")
      ->check(kFinite & CLI::Range(0.0, 3600.0))->capture_default_str();
  app.add_option("--connect-timeout", o.connect_timeout, "s to wait for the first contact point (0: for ever)")
      ->check(kFinite & CLI::Range(0.0, 3600.0))->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    std::tie(o.simulator_address, o.simulator_port) = hil::parse_host_port(simulator, "--simulator");
    hil::UdpVirtualRig rig(load_scene_file(scene_file), o);
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    std::fprintf(stderr, "[INFO] udp_rig_client: port %d, sending to %s\n", rig.port(), simulator.c_str());
    const hil::RigEnd end = rig.run([] { return !g_stop.load(); }, until_ended);
    const auto& s = rig.sequence();
    std::printf("udp_rig_client: %llu measurements sent, %llu missed ticks; contact points: %llu received, %llu lost, "
                "%llu reordered, %llu duplicated, %llu rejected, %llu from other senders; round trip p50 %.1f us, p99 "
                "%.1f us, max %.1f us\n",
                static_cast<unsigned long long>(rig.sent()), static_cast<unsigned long long>(rig.missed_ticks()),
                static_cast<unsigned long long>(s.received()), static_cast<unsigned long long>(s.lost()),
                static_cast<unsigned long long>(s.reordered()), static_cast<unsigned long long>(s.duplicates()),
                static_cast<unsigned long long>(rig.rejected()), static_cast<unsigned long long>(rig.foreign()),
                rig.round_trip().quantile(0.5) * 1e6, rig.round_trip().quantile(0.99) * 1e6, rig.round_trip().max() * 1e6);
    switch (end) {
      case hil::RigEnd::kStopped:
        return 0;
      case hil::RigEnd::kEnded:
        std::printf("udp_rig_client: %s: stopped\n", rig.message().c_str());
        return 0;
      case hil::RigEnd::kContactTimeout:
      case hil::RigEnd::kConnectTimeout:
        std::fprintf(stderr, "[ERROR] udp_rig_client: %s\n", rig.message().c_str());
        return 1;
      case hil::RigEnd::kCannotServe:
        std::fprintf(stderr, "udp_rig_client: --pantograph-scene %s: %s\n", scene_file.c_str(), rig.message().c_str());
        return 2;
    }
    return 0;
  } catch (const hil::HilError& e) {
    std::fprintf(stderr, "udp_rig_client: %s\n", e.what());
    return 2;
  } catch (const SceneError& e) {
    std::fprintf(stderr, "udp_rig_client: --pantograph-scene %s: %s\n", scene_file.c_str(), e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "udp_rig_client: %s\n", e.what());
    return 2;
  }
}
