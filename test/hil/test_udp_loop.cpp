// The loop over UDP (hil::HilLoop + hil::UdpLoopSkin) closed with the simulated rig over UDP
// (hil::UdpVirtualRig) on loopback at 1 kHz, on the wall clock, on config/reference_55m_hil.yaml
// (the whole 550 m pass at 300 km/h: 6.6 s); and delay compensation at two periods of delay.
//
// As test_ros_hil_loop (the same loop over TCPROS), what the wall clock does to the loop is its
// delay, which differs from run to run with the machine's load; a fixed tolerance against the
// internal pantograph on the live pass would fail by chance. So the test compares like with like:
//  1. the pass replayed offline with the delays the live loop had (`measurement_step` of each
//     period) must reproduce the live applied forces period by period (the same numbers through
//     the same operations; the packets carry the float64 values exactly): a difference is a
//     defect of the loop, the packets or the rig;
//  2. the replay with every answer in time must give the internal lumped pantograph's statistics
//     within test_hil.cpp's tolerance for a loop delay of up to two periods (0.1 N on the mean,
//     1 % on the standard deviation of the 20 Hz filtered force).
// The live periods come from the loop's monitoring ring (MonitorRing: lock-free, never blocking
// the loop), which must have dropped none.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>
#include <vector>

#include "catenary_sim/core/simulation.hpp"
#include "catenary_sim/core/output/statistics.hpp"
#include "catenary_sim/hil/loop.hpp"
#include "catenary_sim/hil/report.hpp"
#include "catenary_sim/hil/udp_loop.hpp"
#include "hil_test_support.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;
using namespace catenary_sim::hil;
using namespace hil_test;

namespace {

// The loop and the rig period by period, with the ROS-free frame the UDP loop sends.
bool replay(double dt, int k, const std::vector<std::uint64_t>* measurement_step, Series& out, std::string& error) {
  PointFrame frame;
  return hil_test::replay(dt, k, measurement_step, out, error, [&frame](const Model& m, const State& s, int steps) {
    compute_frame(m, s, steps, frame);
    return Observed{frame.step, frame.speed, frame.pantographs[0].position, frame.pantographs[0].applied_force,
                    wire_points(frame.pantographs[0])};
  });
}

std::string summary_text(const char* what, const ForceStatistics& s) {
  char b[128];
  std::snprintf(b, sizeof b, "%s mean %.3f N std %.3f N", what, s.mean, s.std_dev);
  return b;
}

// The UDP loop of config/reference_55m_hil.yaml on a loopback port of its own, running in a thread
// until stop() (or the end of the test), and a rig socket to talk to it.
struct RunningUdpLoop {
  explicit RunningUdpLoop(const LoopOptions& lo, const Scene& scene = scene_with_dt("reference_55m_hil.yaml", 0.0))
      : loop(scene, lo), skin(loop, loopback()) {
    skin.set_running([this] { return !done.load(); });
    skin.set_log([this](LogLevel, const std::string& t) {
      std::lock_guard<std::mutex> l(log_mu);
      log += t + "\n";
    });
    to = udp_address("127.0.0.1", skin.port(), "simulator");
    runner = std::thread([this] { loop.run(); });
  }
  ~RunningUdpLoop() { stop(); }
  void stop() {
    done = true;
    if (runner.joinable()) runner.join();
  }
  static UdpLoopOptions loopback() {
    UdpLoopOptions uo;
    uo.bind_address = "127.0.0.1";
    uo.port = 0;
    return uo;
  }
  HilLoop loop;
  UdpLoopSkin skin;
  std::atomic<bool> done{false};
  UdpSocket rig{"127.0.0.1", 0, "rig"};
  sockaddr_in to{};
  std::thread runner;
  std::mutex log_mu;
  std::string log;
};

// A measurement packet of one pantograph (a negative force: none, the rig's hello).
csim_udp_measurement measurement(std::uint32_t seq, double f) {
  csim_udp_measurement m;
  std::memset(&m, 0, sizeof m);
  udp::fill_header(m.header, CSIM_UDP_KIND_MEASUREMENT, CSIM_UDP_MEASUREMENT_SIZE, seq, monotonic_ns());
  m.pantographs = f < 0.0 ? 0 : 1;
  m.force[0] = f;
  return m;
}

}  // namespace

TEST(UdpLoop, ClosedOverLoopbackAt1kHzIsItsOwnReplayAndWithoutDelayTheInternalPantograph) {
  const double rate = 1000.0;
  LoopOptions lo;
  lo.rate = rate;
  lo.timeout = 1.0;  // (a stall of the loaded machine holds the measurement: the replay has it)
  lo.at_end = EndAction::kExit;
  lo.who = "test_udp_loop";
  HilLoop loop(scene_with_dt("reference_55m_hil.yaml", 0.0), lo);
  UdpLoopOptions uo;
  uo.bind_address = "127.0.0.1";
  uo.port = 0;  // any free port
  uo.same_clock = true;
  MonitorRing ring;
  UdpLoopSkin skin(loop, uo, &ring);
  std::atomic<bool> done{false};
  skin.set_running([&] { return !done.load(); });
  skin.set_log([](LogLevel, const std::string& t) { std::fprintf(stderr, "%s\n", t.c_str()); });

  UdpRigOptions ro;
  ro.simulator_address = "127.0.0.1";
  ro.simulator_port = skin.port();
  ro.bind_address = "127.0.0.1";
  UdpVirtualRig rig(load_scene_file(test_scenes::kReference), ro);
  std::atomic<bool> rig_stop{false};
  std::thread rig_thread([&] { rig.run([&] { return !rig_stop.load(); }, true); });

  // The monitoring side: drains the ring while the loop runs (as the ROS publisher thread does).
  std::vector<MonitorSample> samples;
  std::atomic<bool> loop_over{false};
  std::thread monitor([&] {
    MonitorSample s;
    while (!loop_over) {
      while (ring.pop(s)) samples.push_back(s);
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    while (ring.pop(s)) samples.push_back(s);
  });
  std::thread watchdog([&] {  // (never a hang: 60 s for a 6.6 s pass)
    for (int i = 0; i < 600 && !loop_over; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    done = true;
  });
  const int rc = loop.run();
  loop_over = true;
  monitor.join();
  watchdog.join();
  rig_stop = true;
  rig_thread.join();
  ASSERT_EQ(rc, 0);
  ASSERT_EQ(loop.mode(), Mode::kEnded) << "the pass did not end within 60 s";
  EXPECT_EQ(ring.dropped(), 0u) << "the monitoring ring dropped samples";
  for (int i = 0; i < static_cast<int>(udp::Reject::kNumReasons); ++i) EXPECT_EQ(skin.rejected()[i], 0u) << i;
  EXPECT_EQ(loop.counters().rejected, 0);
  EXPECT_EQ(loop.counters().holds, 0);

  std::vector<const MonitorSample*> run;
  for (const MonitorSample& s : samples)
    if (s.mode == static_cast<std::uint8_t>(Mode::kRunning) ||
        (s.mode == static_cast<std::uint8_t>(Mode::kEnded) && !run.empty() && s.step > run.back()->step))
      run.push_back(&s);
  ASSERT_GT(run.size(), 1000u);
  const int k = loop.timing().steps_per_period;
  const double dt = loop.model().dt;
  for (std::size_t i = 1; i < run.size(); ++i) ASSERT_EQ(run[i]->step, run[i - 1]->step + k) << i;

  // 1. The live loop is the replay of its own delays.
  Series live;
  std::vector<std::uint64_t> used;
  std::map<long long, std::size_t> late;
  for (const MonitorSample* c : run) {
    live.step.push_back(c->step);
    live.x.push_back(c->position[0]);
    live.f.push_back(c->applied_force[0]);
    used.push_back(c->measurement_step);
    ++late[(static_cast<long long>(c->step) - static_cast<long long>(c->measurement_step)) / k - 1];
  }
  Series same, prompt;
  std::string error;
  ASSERT_TRUE(replay(dt, k, &used, same, error)) << error;
  ASSERT_EQ(same.step.size(), live.step.size());
  std::size_t differ = 0, first = 0;
  for (std::size_t i = 0; i < live.f.size(); ++i) {
    const bool d = same.step[i] != live.step[i] || std::fabs(same.x[i] - live.x[i]) > 1e-9 ||
                   std::fabs(same.f[i] - live.f[i]) > 1e-6;  // (round-off at most: the same operations)
    if (d && differ++ == 0) first = i;
  }
  EXPECT_EQ(differ, 0u) << "first at step " << live.step[first] << ": " << live.f[first] << " N live, "
                        << same.f[first] << " N replayed";

  // 2. Without the delay the loop is the internal pantograph.
  ASSERT_TRUE(replay(dt, k, nullptr, prompt, error)) << error;
  const Model& m = loop.model();
  const ForceStatistics sl = section_stats(m, live, rate), sp = section_stats(m, prompt, rate),
                        si = section_stats(m, internal_series(dt, k), rate);
  // test_hil.cpp, ClosedLoop.DelayOfOneOrTwoPeriodsChangesTheStatisticsLittle: a delay of up to two
  // periods moves the mean < 0.1 N and the standard deviation < 1 %.
  EXPECT_NEAR(sp.mean, si.mean, 0.1);
  EXPECT_NEAR(sp.std_dev, si.std_dev, 0.01 * si.std_dev);

  // The report file's figures: the jitter histogram holds every period that started after the
  // first measurement, and the UDP counts are there.
  nlohmann::ordered_json report = loop_report(loop);
  skin.add_report(report);
  std::uint64_t jitter_periods = 0;
  for (const auto& n : report["jitter"]["counts"]) jitter_periods += n.get<std::uint64_t>();
  EXPECT_EQ(jitter_periods, loop.jitter().count());
  EXPECT_GE(loop.jitter().count(), run.size() - 1);
  const JitterSummary js = summarize_jitter(loop.jitter());
  std::uint64_t in_bins = 0;
  for (std::uint64_t n : js.counts) in_bins += n;
  EXPECT_EQ(in_bins, loop.jitter().count());
  EXPECT_EQ(report["udp"]["packets_received"].get<std::uint64_t>(), skin.sequence().received());
  EXPECT_TRUE(report["coupling"].contains("delay_energy_j"));

  std::string hist;
  for (const auto& [d, n] : late) hist += (hist.empty() ? "" : " ") + std::to_string(d) + ":" + std::to_string(n);
  const auto& q = rig.sequence();
  std::string summary = "UDP 1 kHz, " + std::to_string(run.size()) + " periods (periods late: count " + hist + "); " +
                        summary_text("live", sl) + "; " + summary_text("no delay", sp) + "; " +
                        summary_text("internal", si) + "; latency p99 " +
                        std::to_string(loop.latency().quantile(0.99) * 1e6) + " us; overruns " +
                        std::to_string(loop.counters().overruns) + "; contact points lost " + std::to_string(q.lost()) +
                        ", measurements lost " + std::to_string(skin.sequence().lost()) + "; delay energy " +
                        std::to_string(loop.energy().delay_j) + " J";
  RecordProperty("summary", summary);
  std::printf("test_udp_loop: %s\n", summary.c_str());
}

TEST(UdpLoop, BadLostReorderedAndDuplicatedPacketsAreCountedAndChangeNothing) {
  // A rig that misbehaves, packet by packet, against the running loop: a hello, measurement 1,
  // then a duplicate of 1, measurement 3, a late 2 (reordered), a NaN force, a short packet, a
  // force out of range and one out of range numbered far ahead, then a good one. Only 1, 3 and
  // the last may reach the loop; every other one is counted, and none changes the force in effect
  // or the sequence tracking (a number taken from a refused packet would drop the last one).
  LoopOptions lo;
  lo.rate = 1000.0;
  lo.timeout = 5.0;
  lo.who = "test_udp_loop";
  RunningUdpLoop run(lo);
  HilLoop& loop = run.loop;
  UdpLoopSkin& skin = run.skin;
  auto send = [&](const csim_udp_measurement& m, std::size_t size = sizeof(csim_udp_measurement)) {
    ASSERT_TRUE(run.rig.send(&m, size, run.to));
    std::this_thread::sleep_for(std::chrono::milliseconds(30));  // (one at a time through the loop)
  };
  send(measurement(1, -1.0));   // hello
  send(measurement(2, 120.0));  // 1st measurement: the pass starts
  send(measurement(2, 500.0));  // duplicate
  send(measurement(4, 130.0));  // 3 skipped
  send(measurement(3, 700.0));  // late
  send(measurement(5, std::nan("")));
  send(measurement(6, 150.0), 40);  // short
  send(measurement(7, 5000.0));     // out of range (the loop's check, shared with ROS)
  send(measurement(60, 5000.0));    // out of range, numbered far ahead
  send(measurement(8, 140.0));      // good: taken
  run.stop();
  const auto& seq = skin.sequence();
  EXPECT_EQ(seq.newest(), 8u);
  EXPECT_EQ(seq.duplicates(), 1u);
  EXPECT_EQ(seq.reordered(), 1u);
  // 3 came, late; 5, 6 and 7 came and were rejected (counted so), so none is lost.
  EXPECT_EQ(seq.lost(), 0u);
  EXPECT_EQ(skin.unusable(), 2u);
  EXPECT_EQ(skin.rejected()[static_cast<int>(udp::Reject::kNonFinite)], 1u);
  EXPECT_EQ(skin.rejected()[static_cast<int>(udp::Reject::kSize)], 1u);
  EXPECT_EQ(loop.counters().accepted, 3);
  EXPECT_EQ(loop.counters().rejected, 4);  // NaN, short, two out of range
  EXPECT_EQ(loop.mode(), Mode::kRunning);
  // The force in effect is the last good measurement's, not a rejected or stale one.
  EXPECT_DOUBLE_EQ(loop.state().external_force[loop.external()[0]], 140.0);
}

TEST(UdpLoop, ARigThatFallsSilentPutsTheLineIntoTheSafeHold) {
  // The safe hold is the loop's (test_ros_hil_safety covers it through the topics): over UDP too,
  // a rig silent for longer than the timeout stops the train and ramps the force, and the contact
  // points keep coming, finite, with the SAFE_HOLD mode in their state flags.
  LoopOptions lo;
  lo.rate = 1000.0;
  lo.timeout = 0.1;
  lo.hold_ramp = 0.1;
  lo.who = "test_udp_loop";
  RunningUdpLoop run(lo);
  HilLoop& loop = run.loop;
  UdpSocket& rig = run.rig;
  const csim_udp_measurement m = measurement(1, 120.0);
  ASSERT_TRUE(rig.send(&m, sizeof m, run.to));
  // Then silent. Read the contact points until one says SAFE_HOLD (at most 10 s: the timeout is
  // 0.1 s), then for 0.3 s more: they keep coming, finite (decoded), all in the hold.
  alignas(8) std::uint8_t buf[2048];
  bool holding = false;
  std::size_t in_hold = 0, not_hold_after = 0;
  const double deadline = steady_now() + 10.0;
  double hold_seen = 0.0;
  while (steady_now() < deadline && (!holding || steady_now() < hold_seen + 0.3)) {
    if (!rig.wait_readable(steady_now() + 0.05)) continue;
    sockaddr_in from{};
    const long n = rig.receive(buf, sizeof buf, &from);
    if (n < 0) continue;
    csim_udp_contact_point p;
    udp::Reject why;
    std::string reason;
    ASSERT_TRUE(udp::decode_contact_point(buf, static_cast<std::size_t>(n), p, why, reason)) << reason;
    const bool hold = (p.state_flags & CSIM_UDP_MODE_MASK) == CSIM_UDP_MODE_SAFE_HOLD;
    if (hold && !holding) {
      holding = true;
      hold_seen = steady_now();
    }
    if (holding) (hold ? in_hold : not_hold_after)++;
  }
  run.stop();
  ASSERT_TRUE(holding) << "no SAFE_HOLD contact point within 10 s of silence";
  EXPECT_GE(in_hold, 10u);  // (one a period: about 300 in 0.3 s; 10 tolerates a loaded machine)
  EXPECT_EQ(not_hold_after, 0u);
  EXPECT_EQ(loop.counters().holds, 1);
  EXPECT_EQ(loop.mode(), Mode::kHold);
}

// config/reference_55m_hil.yaml made 3-D: the contact wire staggered +-0.3 m, the head 1.2 m wide
// swaying 0.5 m at 2 Hz, so the contact point leaves the working width in the first span, long
// before the analysis section; the scene asks the pass to stop there.
Scene dewiring_scene() {
  return test_scenes::edited_scene("reference_55m_hil.yaml", [](YAML::Node& root) {
    root["stagger"]["contact_wire"] = std::vector<double>{0.3, -0.3};
    root["stagger"]["messenger"] = std::vector<double>{0.0};
    root["stagger"]["steady_arm_stiffness"] = 2.0e5;
    root["pantograph_head"]["working_width"] = 1.2;
    root["pantograph_head"]["on_dewirement"] = "stop";
    root["pantograph_head"]["sway"]["amplitude"] = 0.5;
    root["pantograph_head"]["sway"]["frequency"] = 2.0;
  });
}

TEST(UdpLoop, APassStoppedByADewirementIsReportedAsSuchAndNotRestarted) {
  // dewiring_scene() with at_end loop: the pass must not start again as if it had reached its
  // end: it ends, the log says the dewirement, the end packet gives its reason, and there are no
  // statistics to write (as simulate_pass).
  const Scene scene = dewiring_scene();
  LoopOptions lo;
  lo.rate = 1000.0;
  lo.timeout = 5.0;
  lo.at_end = EndAction::kLoop;
  lo.who = "test_udp_loop";
  RunningUdpLoop run(lo, scene);
  HilLoop& loop = run.loop;
  // The rig: 100 N every millisecond, reading what comes back, until an end packet (at most 60 s
  // of wall clock: the dewirement comes within 0.2 s of simulation, however far the loop falls behind).
  std::vector<std::uint32_t> reasons;
  alignas(8) std::uint8_t buf[2048];
  const double deadline = steady_now() + 60.0;
  for (std::uint32_t seq = 1; reasons.empty() && steady_now() < deadline; ++seq) {
    const csim_udp_measurement m = measurement(seq, 100.0);
    ASSERT_TRUE(run.rig.send(&m, sizeof m, run.to));
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    sockaddr_in from{};
    long n;
    while ((n = run.rig.receive(buf, sizeof buf, &from)) >= 0) {
      csim_udp_end e;
      udp::Reject why;
      std::string reason;
      if (udp::kind_of(buf, static_cast<std::size_t>(n)) == CSIM_UDP_KIND_END &&
          udp::decode_end(buf, static_cast<std::size_t>(n), e, why, reason))
        reasons.push_back(e.reason);
    }
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(50));  // (the loop goes on: a restart would show)
  run.stop();
  ASSERT_FALSE(reasons.empty()) << "no end packet within 60 s\n" << run.log;
  EXPECT_EQ(reasons.front(), CSIM_UDP_END_DEWIRED);
  EXPECT_STREQ(udp::end_reason_name(CSIM_UDP_END_DEWIRED), "the pass stopped at a dewirement");
  EXPECT_TRUE(loop.dewired());
  EXPECT_FALSE(loop.diverged());
  EXPECT_EQ(loop.mode(), Mode::kEnded);
  EXPECT_EQ(loop.pass_count(), 0u) << "the pass started again";
  EXPECT_NE(run.log.find("dewirement of pantograph leading at"), std::string::npos) << run.log;
  EXPECT_EQ(run.log.find("finished"), std::string::npos) << run.log;
  State end_state;
  const std::unique_ptr<PassRecorder> rec = run.skin.take_finished(&end_state);
  ASSERT_TRUE(rec);
  EXPECT_EQ(end_state.status, StepStatus::kDewired);
  std::string why;
  const std::string text = pass_stats_json(loop.model(), end_state, rec->statistics(loop.model()), RunInfo{}, &why);
  EXPECT_TRUE(text.empty()) << text;
  EXPECT_NE(why.find("dewirement before it crossed the analysis section"), std::string::npos) << why;
}

TEST(UdpLoop, TheEndPacketAfterTheLoopReturnedCarriesTheStepAtTheEnd) {
  // With at_end exit (catenary_sim_hil_udp's default) the loop returns at the end of the pass and
  // the end packet is sent after it (finish()): its step is the last contact point's, as the
  // packet's description says, not 0.
  LoopOptions lo;
  lo.rate = 1000.0;
  lo.timeout = 5.0;
  lo.at_end = EndAction::kExit;
  lo.who = "test_udp_loop";
  RunningUdpLoop run(lo, dewiring_scene());
  std::uint64_t last_step = 0;
  alignas(8) std::uint8_t buf[2048];
  auto drain = [&](std::vector<csim_udp_end>& ends) {
    sockaddr_in from{};
    long n;
    while ((n = run.rig.receive(buf, sizeof buf, &from)) >= 0) {
      const std::size_t size = static_cast<std::size_t>(n);
      udp::Reject why;
      std::string reason;
      csim_udp_contact_point p;
      csim_udp_end e;
      if (udp::kind_of(buf, size) == CSIM_UDP_KIND_END && udp::decode_end(buf, size, e, why, reason)) ends.push_back(e);
      else if (udp::decode_contact_point(buf, size, p, why, reason)) last_step = p.step;
    }
  };
  std::vector<csim_udp_end> ends;
  const double deadline = steady_now() + 60.0;  // (as above: the end comes within 0.2 s of simulation)
  for (std::uint32_t seq = 1; run.loop.mode() != Mode::kEnded && steady_now() < deadline; ++seq) {
    const csim_udp_measurement m = measurement(seq, 100.0);
    ASSERT_TRUE(run.rig.send(&m, sizeof m, run.to));
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    drain(ends);
  }
  run.stop();  // (the loop has returned: exit)
  ASSERT_EQ(run.loop.mode(), Mode::kEnded);
  drain(ends);
  EXPECT_TRUE(ends.empty()) << "an end packet before the loop returned";
  run.skin.finish();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  drain(ends);
  ASSERT_EQ(ends.size(), 3u);  // (three copies)
  ASSERT_GT(last_step, 0u);
  for (const csim_udp_end& e : ends) {
    EXPECT_EQ(e.step, last_step);
    EXPECT_EQ(e.reason, CSIM_UDP_END_DEWIRED);
  }
}
