// Bad input to the UDP loop's command line and its real-time options: each run (a child process
// of catenary_sim_hil_udp or udp_rig_client) must fail cleanly (exit 2, no signal, no hang) with
// an error naming the option, the value and what is allowed; the real-time checks name their
// option too. The tests run as root here, so "not permitted" is provoked by running the child
// without CAP_SYS_NICE and CAP_IPC_LOCK and with an rtprio limit of 0 (setpriv, prlimit: util-linux).
#include <gtest/gtest.h>
#include <unistd.h>

#include <yaml-cpp/yaml.h>

#include <chrono>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "../support/child_process.hpp"
#include "catenary_sim/hil/realtime.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim_test;
using catenary_sim::hil::RealtimeOptions;

namespace {

const std::string kSim = test_scenes::program("catenary_sim_hil_udp");
const std::string kRig = test_scenes::program("udp_rig_client");
const std::string& kHil = test_scenes::kReferenceHil;
const std::string& kLumped = test_scenes::kReference;

ChildRun run(const std::vector<std::string>& args, const std::vector<std::string>& prefix = {}) {
  std::vector<std::string> a = prefix;
  a.insert(a.end(), args.begin(), args.end());
  char dir[] = "/tmp/catenary_sim_udp_cli_XXXXXX";
  const std::string d = mkdtemp(dir);
  return run_child(a, d + "/output.txt", 60.0);
}

void expect_refused(const std::vector<std::string>& args, const std::vector<std::string>& names,
                    const std::vector<std::string>& prefix = {}) {
  const ChildRun r = run(args, prefix);
  std::string cmd;
  for (const std::string& s : args) cmd += " " + s;
  EXPECT_FALSE(r.hung) << cmd;
  EXPECT_EQ(r.signal, 0) << cmd;
  EXPECT_NE(r.exit_code, 0) << cmd << "\n" << r.out;
  EXPECT_NE(r.exit_code, -1) << cmd;
  for (const std::string& n : names) EXPECT_NE(r.out.find(n), std::string::npos) << cmd << ": '" << n << "' not in\n" << r.out;
}

}  // namespace

TEST(HilUdpCli, BadOptionsAreRefusedNamingTheOption) {
  const std::vector<std::string> base = {kSim, "--scene", kHil, "--port", "0", "--duration", "1"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> a = base;
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  };
  expect_refused(with({"--rate", "500"}), {"--rate", "500"});
  expect_refused(with({"--rate", "nan"}), {"--rate", "nan"});
  // The loop's own limits and words, as the ROS node's ~hil/rate says them.
  expect_refused(with({"--rate", "20000"}), {"--rate = 20000 rejected: allowed [1000, 10000] Hz"});
  expect_refused(with({"--timeout", "0.0015", "--rate", "1000"}), {"timeout", "0.0015", "allowed"});
  expect_refused(with({"--delay-compensation", "0.5"}), {"--delay-compensation"});
  // (beyond the core's limit on the train's acceleration: refused by the option, not by the loop)
  expect_refused(with({"--hold-deceleration", "30"}), {"--hold-deceleration", "30"});
  expect_refused(with({"--rig", "localhost"}), {"--rig", "HOST:PORT"});
  expect_refused(with({"--rig", "127.0.0.1:0"}), {"--rig", "1 to 65535"});
  expect_refused(with({"--rig", "example.org:47801"}), {"--rig", "IPv4"});
  expect_refused(with({"--bind", "300.1.1.1"}), {"300.1.1.1", "IPv4"});
  expect_refused(with({"--port", "70000"}), {"--port", "70000"});
  expect_refused(with({"--at-end", "repeat"}), {"--at-end", "repeat"});
  expect_refused(with({"--fifo-priority", "100"}), {"--fifo-priority", "100"});
  expect_refused(with({"--cpus", "9999"}), {"--cpus", "9999", "does not exist"});
  expect_refused(with({"--cpus", "1-a"}), {"--cpus", "1-a", "allowed"});
  expect_refused(with({"--cpus", ""}), {"--cpus"});
  expect_refused({kSim, "--scene", kLumped, "--port", "0", "--duration", "1"}, {"external"});
  expect_refused({kSim, "--scene", "/nonexistent.yaml"}, {"--scene", "/nonexistent.yaml"});
  {
    // A scene whose frames do not fit a packet (five external pantographs) is --scene's fault.
    char dir[] = "/tmp/catenary_sim_udp_cli_XXXXXX";
    const std::string five = test_scenes::with_pantograph_copies(kHil, 5, std::string(mkdtemp(dir)) + "/five.yaml");
    const ChildRun r = run({kSim, "--scene", five, "--port", "0", "--duration", "1"});
    EXPECT_EQ(r.exit_code, 2) << r.out;
    EXPECT_NE(r.out.find("--scene " + five + ": the scene has 5 external pantographs"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("~scene"), std::string::npos) << r.out;
  }
  expect_refused({kRig, "--pantograph-scene", kLumped, "--simulator", "127.0.0.1"}, {"--simulator", "HOST:PORT"});
  expect_refused({kRig, "--pantograph-scene", kHil, "--simulator", "127.0.0.1:47800"}, {"lumped"});
  expect_refused({kRig, "--pantograph-scene", kLumped, "--rate", "-1"}, {"--rate"});
  // A scene the rig cannot take: a pantograph with heads on their own suspensions.
  expect_refused({kRig, "--pantograph-scene", test_scenes::kReferenceTwoHeads},
                 {"--pantograph-scene", "two_heads", "heads", "allowed"});
  expect_refused({kRig, "--pantograph-scene", kLumped, "--simulator", "0.0.0.0:47800"}, {"--simulator", "unicast"});
  expect_refused({kRig, "--pantograph-scene", kLumped, "--simulator", "127.0.0.1:65536"}, {"--simulator", "1 to 65535"});
  expect_refused({kRig, "--pantograph-scene", kLumped, "--timeout", "-1"}, {"--timeout", "-1"});
  expect_refused({kRig, "--pantograph-scene", kLumped, "--connect-timeout", "nan"}, {"--connect-timeout", "nan"});
  expect_refused(with({"--rig", "255.255.255.255:47801"}), {"--rig", "unicast"});
  expect_refused(with({"--allow", "10.0.0.2:0"}), {"--allow", "10.0.0.2:0", "allowed"});
  expect_refused(with({"--allow", "10.0.0.2", "--rig", "10.0.0.3:47801"}), {"--rig", "allow"});
}

TEST(HilUdpCli, TheDocsPairEndsTogether) {
  // docs/hil.md's ROS-free pair: the simulator runs the pass and exits, and tells the rig, which
  // exits too (by itself: the 60 s limit of run_child is never reached on a 6.6 s pass).
  const int port = free_port();
  ASSERT_GT(port, 0);
  ChildRun sim;
  std::thread t([&] { sim = run({kSim, "--scene", kHil, "--port", std::to_string(port), "--bind", "127.0.0.1"}); });
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const ChildRun rig = run({kRig, "--pantograph-scene", kLumped, "--simulator", "127.0.0.1:" + std::to_string(port)});
  t.join();
  EXPECT_FALSE(rig.hung) << rig.out;
  EXPECT_EQ(rig.exit_code, 0) << rig.out;
  EXPECT_NE(rig.out.find("the pass ended"), std::string::npos) << rig.out;
  EXPECT_FALSE(sim.hung) << sim.out;
  EXPECT_EQ(sim.exit_code, 0) << sim.out;
}

TEST(HilUdpCli, RealTimeRefusedWithoutTheRightNamesTheOption) {
  if (geteuid() != 0 || access("/usr/bin/setpriv", X_OK) != 0 || access("/usr/bin/prlimit", X_OK) != 0)
    GTEST_SKIP() << "needs root, setpriv and prlimit (util-linux)";
  // As root without CAP_SYS_NICE and CAP_IPC_LOCK (dropped from the bounding set, so the exec
  // cannot regain them) and with an rtprio limit of 0: SCHED_FIFO is refused, with the option
  // named. Not as another user: a build under /root (the fresh-machine check's clone, mode 0700)
  // cannot even load its libraries as nobody.
  const std::vector<std::string> without_rights = {"/usr/bin/prlimit", "--rtprio=0:0", "/usr/bin/setpriv",
                                           "--bounding-set=-sys_nice,-ipc_lock", "--inh-caps=-sys_nice,-ipc_lock", "--"};
  const std::vector<std::string> base = {kSim, "--scene", kHil, "--port", "0", "--duration", "1"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> a = base;
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  };
  expect_refused(with({"--fifo-priority", "50"}), {"--fifo-priority", "50", "not permitted"}, without_rights);
}

TEST(Realtime, ChecksNameTheOptionAndApplyAsRoot) {
  RealtimeOptions o;
  o.priority_name = "~hil/realtime_priority";
  o.cpus_name = "~hil/cpus";
  o.fifo_priority = 100;
  EXPECT_NE(catenary_sim::hil::check_realtime(o).find("~hil/realtime_priority = 100"), std::string::npos);
  o.fifo_priority = -3;
  EXPECT_NE(catenary_sim::hil::check_realtime(o).find("allowed"), std::string::npos);
  o.fifo_priority = 0;
  o.cpus = {100000};
  EXPECT_NE(catenary_sim::hil::check_realtime(o).find("~hil/cpus = 100000"), std::string::npos);
  EXPECT_THROW(catenary_sim::hil::parse_cpu_list("0-", "~hil/cpus"), std::invalid_argument);
  EXPECT_THROW(catenary_sim::hil::parse_cpu_list("3-1", "~hil/cpus"), std::invalid_argument);
  EXPECT_EQ(catenary_sim::hil::parse_cpu_list("0-2,5", "x"), (std::vector<int>{0, 1, 2, 5}));
  if (geteuid() != 0) GTEST_SKIP() << "applying needs root";
  // Applied on a thread of its own (the test's main thread keeps its scheduling).
  std::string err = "not run";
  std::thread t([&] {
    RealtimeOptions ok;
    ok.fifo_priority = 10;
    ok.cpus = {0};
    err = catenary_sim::hil::apply_realtime(ok);
  });
  t.join();
  EXPECT_EQ(err, "");
}
