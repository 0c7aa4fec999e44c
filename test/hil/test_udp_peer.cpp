// The UDP loop follows the rig it was armed with, over loopback (127.0.0.1) with bounded loops:
// a rig that restarts (a new socket saying hello, or the same socket numbering from 1 again) and
// one whose sequence jumps far ahead are followed again within a few packets; a second sender is
// ignored and counted, and gets no contact point; a sender not on the allow-list is refused. The
// rig's side: the end packet stops the example rig, and so does silence after --timeout.
//
// The checks count the measurements the loop took (LoopCounters::accepted): every valid, newer
// measurement of the rig is taken whatever the machine's timing (the loop drains its socket), so
// the counts are exact, not timing-dependent.
#include <gtest/gtest.h>

#include <atomic>
#include <cctype>
#include <chrono>
#include <cstring>
#include <fstream>
#include <memory>
#include <random>
#include <regex>
#include <sstream>
#include <thread>

#include "catenary_sim/hil/loop.hpp"
#include "catenary_sim/hil/udp_loop.hpp"
#include "hil_test_support.hpp"
#include "../support/scenes.hpp"

using namespace catenary_sim;
using namespace catenary_sim::hil;
using namespace hil_test;

namespace {

struct Loop {
  explicit Loop(const UdpLoopOptions& uo) : loop(scene_with_dt("reference_55m_hil.yaml", 0.0), options()), skin(loop, uo) {
    skin.set_running([this] { return !done.load(); });
    skin.set_log([this](LogLevel, const std::string& t) {
      std::lock_guard<std::mutex> l(log_mu);
      log += t + "\n";
    });
    to = udp_address("127.0.0.1", skin.port(), "simulator");
    runner = std::thread([this] { loop.run(); });
  }
  ~Loop() { stop(); }
  static LoopOptions options() {
    LoopOptions lo;
    lo.rate = 1000.0;
    lo.timeout = 5.0;  // (no safe hold in these tests: each lasts well under 5 s)
    lo.who = "test_udp_peer";
    return lo;
  }
  static UdpLoopOptions loopback(std::vector<AllowedSender> allow = {}) {
    UdpLoopOptions uo;
    uo.bind_address = "127.0.0.1";
    uo.port = 0;
    uo.allow = std::move(allow);
    return uo;
  }
  void stop() {
    // (let the loop drain what was sent: a period or two)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    done = true;
    if (runner.joinable()) runner.join();
  }
  HilLoop loop;
  UdpLoopSkin skin;
  std::atomic<bool> done{false};
  sockaddr_in to{};
  std::thread runner;
  std::mutex log_mu;
  std::string log;
};

// Sends a hello (f < 0) or a measurement of force f, numbered `seq`, about one per millisecond
// (a rig at 1 kHz).
void send(UdpSocket& s, const sockaddr_in& to, std::uint32_t seq, double f) {
  csim_udp_measurement m;
  std::memset(&m, 0, sizeof m);
  udp::fill_header(m.header, CSIM_UDP_KIND_MEASUREMENT, CSIM_UDP_MEASUREMENT_SIZE, seq, monotonic_ns());
  m.pantographs = f < 0.0 ? 0 : 1;
  m.force[0] = f;
  ASSERT_TRUE(s.send(&m, sizeof m, to));
  std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

// The contact points waiting at `s` (after `wait` s).
std::vector<csim_udp_contact_point> contact_points(UdpSocket& s, double wait = 0.1) {
  std::this_thread::sleep_for(std::chrono::duration<double>(wait));
  std::vector<csim_udp_contact_point> out;
  alignas(8) std::uint8_t buf[2048];
  sockaddr_in from{};
  long n;
  while ((n = s.receive(buf, sizeof buf, &from)) >= 0) {
    csim_udp_contact_point p;
    udp::Reject why;
    std::string reason;
    if (udp::decode_contact_point(buf, static_cast<std::size_t>(n), p, why, reason)) out.push_back(p);
  }
  return out;
}

}  // namespace

TEST(UdpPeer, ARigRestartedWithANewSocketIsFollowedAtItsHello) {
  Loop l(Loop::loopback());
  {
    UdpSocket a("127.0.0.1", 0, "rig");
    send(a, l.to, 1, -1.0);
    for (std::uint32_t s = 2; s <= 301; ++s) send(a, l.to, s, 120.0);
  }  // (the rig's process ends: its socket closes)
  UdpSocket b("127.0.0.1", 0, "rig");
  send(b, l.to, 1, -1.0);  // the restarted rig says hello from its new port, then measures
  for (std::uint32_t s = 2; s <= 21; ++s) send(b, l.to, s, 130.0);
  const auto points = contact_points(b);
  l.stop();
  // Every measurement of the restarted rig is taken: none is mistaken for a late one.
  EXPECT_EQ(l.loop.counters().accepted, 300 + 20);
  EXPECT_EQ(l.skin.unusable(), 0u);
  EXPECT_EQ(l.skin.rig_moves(), 1u);
  ASSERT_FALSE(points.empty()) << "the restarted rig gets no contact point";
  EXPECT_EQ(points.back().pantograph[0].applied_force, 130.0);
  EXPECT_NE(l.log.find("moved"), std::string::npos) << l.log;
}

TEST(UdpPeer, ARigNumberingAgainFromOneOnItsSocketIsFollowedWithinEightPackets) {
  Loop l(Loop::loopback());
  UdpSocket a("127.0.0.1", 0, "rig");
  send(a, l.to, 1, -1.0);
  for (std::uint32_t s = 2; s <= 301; ++s) send(a, l.to, s, 120.0);
  for (std::uint32_t s = 1; s <= 20; ++s) send(a, l.to, s, 130.0);  // restarted without a hello
  l.stop();
  // The first kResyncRun - 1 renumbered ones are dropped as late; the kResyncRun-th in a row is
  // taken as the rig's numbering, and the rest with it.
  const int run = udp::SequenceTracker::kResyncRun;
  EXPECT_EQ(l.loop.counters().accepted, 300 + 20 - (run - 1));
  EXPECT_EQ(l.skin.unusable(), static_cast<std::uint64_t>(run - 1));
  EXPECT_EQ(l.skin.sequence().restarts(), 1u);
  EXPECT_EQ(l.loop.state().external_force[l.loop.external()[0]], 130.0);
  EXPECT_NE(l.log.find("numbers its packets again"), std::string::npos) << l.log;
}

TEST(UdpPeer, ASequenceJumpIsFollowedWithinEightPackets) {
  Loop l(Loop::loopback());
  UdpSocket a("127.0.0.1", 0, "rig");
  send(a, l.to, 1, -1.0);
  for (std::uint32_t s = 2; s <= 51; ++s) send(a, l.to, s, 120.0);
  send(a, l.to, 5051, 125.0);  // one packet 5,000 ahead
  for (std::uint32_t s = 52; s <= 101; ++s) send(a, l.to, s, 130.0);
  l.stop();
  const int run = udp::SequenceTracker::kResyncRun;
  EXPECT_EQ(l.loop.counters().accepted, 50 + 1 + 50 - (run - 1));
  EXPECT_EQ(l.loop.state().external_force[l.loop.external()[0]], 130.0);
  EXPECT_EQ(l.loop.counters().holds, 0);
}

TEST(UdpPeer, ASecondSenderIsIgnoredCountedAndLoggedAndGetsNoContactPoint) {
  Loop l(Loop::loopback());
  UdpSocket rig("127.0.0.1", 0, "rig"), other("127.0.0.1", 0, "other");
  send(rig, l.to, 1, -1.0);
  for (std::uint32_t s = 2; s <= 201; ++s) {
    send(rig, l.to, s, 120.0);
    send(other, l.to, s + 1, 500.0);  // just ahead of the rig, a force the rig never measured
  }
  const auto at_rig = contact_points(rig, 0.0), at_other = contact_points(other);
  l.stop();
  EXPECT_EQ(l.loop.counters().accepted, 200);
  EXPECT_EQ(l.skin.foreign(), 200u);
  EXPECT_TRUE(at_other.empty()) << at_other.size() << " contact points went to the second sender";
  ASSERT_FALSE(at_rig.empty());
  for (const auto& p : at_rig) ASSERT_LE(p.pantograph[0].applied_force, 120.0) << "a foreign force was applied";
  EXPECT_EQ(l.loop.state().external_force[l.loop.external()[0]], 120.0);
  EXPECT_NE(l.log.find("ignored"), std::string::npos) << l.log;
}

TEST(UdpPeer, ASenderNotOnTheAllowListIsRefused) {
  UdpSocket rig("127.0.0.1", 0, "rig"), other("127.0.0.1", 0, "other");
  Loop l(Loop::loopback(parse_allow_list("127.0.0.1:" + std::to_string(rig.port()), "--allow")));
  // The stranger speaks first: with no allow-list it would become the rig.
  send(other, l.to, 1, -1.0);
  for (std::uint32_t s = 2; s <= 21; ++s) send(other, l.to, s, 500.0);
  send(rig, l.to, 1, -1.0);
  for (std::uint32_t s = 2; s <= 21; ++s) send(rig, l.to, s, 120.0);
  const auto at_other = contact_points(other);
  l.stop();
  EXPECT_EQ(l.skin.refused(), 21u);
  EXPECT_EQ(l.loop.counters().accepted, 20);
  EXPECT_EQ(l.loop.counters().rejected, 0);
  EXPECT_TRUE(at_other.empty());
  EXPECT_EQ(l.loop.state().external_force[l.loop.external()[0]], 120.0);
  EXPECT_NE(l.log.find("allow-list"), std::string::npos) << l.log;
}

// Fuzz of sequences and senders (seeded, so every run sends the same packets): the armed rig's
// numbering jumps ahead, falls back, repeats and restarts at random, while strangers on other
// ports send measurements of 500 N with random sequence numbers, some just ahead of the rig's.
// Whatever they send, no stranger gets a contact point or has its force applied, and after the
// rig's last run of kResyncRun + 2 packets in order the force in effect is the rig's last.
TEST(UdpPeer, FuzzedSequencesAndSendersNeverTakeTheLoop) {
  const int run = udp::SequenceTracker::kResyncRun;
  for (unsigned seed = 1; seed <= 4; ++seed) {
    std::mt19937 rng(seed);
    Loop l(Loop::loopback());
    UdpSocket rig("127.0.0.1", 0, "rig"), s1("127.0.0.1", 0, "stranger"), s2("127.0.0.1", 0, "stranger");
    UdpSocket* strangers[] = {&s1, &s2};
    std::uint32_t seq = 1;
    send(rig, l.to, seq, -1.0);  // armed with the rig's hello
    for (int k = 0; k < 300; ++k) {
      switch (rng() % 8) {
        case 0: seq += 1 + rng() % 100000; break;   // a jump ahead
        case 1: seq = 1 + rng() % (seq + 1); break;  // a fall back, or a restart from low numbers
        case 2: break;                               // a repeat
        default: ++seq;                              // in order
      }
      send(rig, l.to, seq, 120.0 + (k % 7));
      if (rng() % 2) {
        UdpSocket* s = strangers[rng() % 2];
        const std::uint32_t sseq = (rng() % 3 == 0) ? seq + 1 : static_cast<std::uint32_t>(rng());
        send(*s, l.to, sseq, 500.0);
      }
    }
    double last = 0.0;
    for (int k = 0; k < run + 2; ++k) send(rig, l.to, ++seq, last = 140.0 + k);
    const auto at_rig = contact_points(rig, 0.0), at_s1 = contact_points(s1, 0.0), at_s2 = contact_points(s2);
    l.stop();
    EXPECT_TRUE(at_s1.empty() && at_s2.empty()) << "seed " << seed << ": a stranger got contact points";
    for (const auto& p : at_rig) ASSERT_LT(p.pantograph[0].applied_force, 500.0) << "seed " << seed;
    EXPECT_EQ(l.loop.state().external_force[l.loop.external()[0]], last) << "seed " << seed << "\n" << l.log;
    EXPECT_GT(l.skin.foreign(), 0u) << "seed " << seed;
  }
}

TEST(UdpPeer, AllowListEntriesAreCheckedNamingTheOption) {
  EXPECT_EQ(parse_allow_list("", "--allow").size(), 0u);
  const auto a = parse_allow_list("10.0.0.2,10.0.0.3:47801", "--allow");
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a[0].port, 0);
  EXPECT_EQ(a[1].port, 47801);
  for (const char* bad : {"10.0.0.2:0", "10.0.0.2:65536", "host", "10.0.0.2,", "1.2.3.4.5", "10.0.0.2:x"}) {
    try {
      parse_allow_list(bad, "--allow");
      ADD_FAILURE() << bad << " accepted";
    } catch (const HilError& e) {
      EXPECT_NE(std::string(e.what()).find("--allow"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("allowed"), std::string::npos) << e.what();
    }
  }
}

namespace {

// A stand-in simulator on loopback for the example rig: answers its hello with contact points of
// one pantograph (the reference line's contact-wire height, at rest).
struct FakeSimulator {
  UdpSocket socket{"127.0.0.1", 0, "simulator"};
  sockaddr_in rig{};
  std::uint32_t sequence = 0;
  bool wait_for_rig(double seconds) {
    alignas(8) std::uint8_t buf[2048];
    const double until = steady_now() + seconds;
    while (steady_now() < until) {
      socket.wait_readable(steady_now() + 0.05);
      if (socket.receive(buf, sizeof buf, &rig) >= 0) return true;
    }
    return false;
  }
  void contact_point(std::uint64_t step) {
    csim_udp_contact_point p;
    std::memset(&p, 0, sizeof p);
    udp::fill_header(p.header, CSIM_UDP_KIND_CONTACT_POINT, CSIM_UDP_CONTACT_POINT_SIZE, ++sequence, monotonic_ns());
    p.step = step;
    p.state_flags = CSIM_UDP_MODE_RUNNING;
    p.pantographs = 1;
    p.steps_per_period = 2;
    p.dt = 0.0005;
    p.speed = 83.3;
    p.pantograph[0].height = 5.3;
    p.pantograph[0].wire_points = 1;
    p.pantograph[0].on_wire[0] = 1;
    p.pantograph[0].wire_height[0] = 5.3;
    socket.send(&p, sizeof p, rig);
  }
  void end(std::uint32_t reason) {
    csim_udp_end e;
    std::memset(&e, 0, sizeof e);
    udp::fill_header(e.header, CSIM_UDP_KIND_END, CSIM_UDP_END_SIZE, ++sequence, monotonic_ns());
    e.reason = reason;
    socket.send(&e, sizeof e, rig);
  }
};

// The example rig against `sim` in a thread, stopped by the test after 20 s at the latest (never a
// hang); returns how it ended and how long it ran.
struct RigRun {
  RigEnd end = RigEnd::kStopped;
  double seconds = 0.0;  // from the start of run()
  double finished = 0.0;  // steady s
  std::string message;
};
RigRun run_rig(FakeSimulator& sim, const std::function<void()>& script, double contact_timeout, double connect_timeout) {
  UdpRigOptions o;
  o.simulator_address = "127.0.0.1";
  o.simulator_port = sim.socket.port();
  o.bind_address = "127.0.0.1";
  o.contact_timeout = contact_timeout;
  o.connect_timeout = connect_timeout;
  UdpVirtualRig rig(load_scene_file(test_scenes::kReference), o);
  RigRun r;
  const double start = steady_now();
  std::thread t([&] {
    r.end = rig.run([&] { return steady_now() - start < 20.0; }, true);
    r.finished = steady_now();
    r.seconds = r.finished - start;
  });
  script();
  t.join();
  r.message = rig.message();
  return r;
}

}  // namespace

TEST(UdpRigEnd, TheEndPacketStopsTheRig) {
  FakeSimulator sim;
  double sent_end = 0.0;
  const RigRun r = run_rig(sim, [&] {
    ASSERT_TRUE(sim.wait_for_rig(5.0));
    for (std::uint64_t k = 1; k <= 100; ++k) {
      sim.contact_point(2 * k);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    sent_end = steady_now();
    sim.end(CSIM_UDP_END_FINISHED);
  }, 10.0, 10.0);
  EXPECT_EQ(r.end, RigEnd::kEnded) << r.message;
  // (well before its 10 s timeout: the end packet, not silence, stopped it)
  EXPECT_LT(r.finished - sent_end, 5.0);
  EXPECT_NE(r.message.find("the pass ended"), std::string::npos) << r.message;
}

TEST(UdpRigEnd, SilenceAfterContactPointsStopsTheRigAfterItsTimeout) {
  FakeSimulator sim;
  double silent_from = 0.0;
  const RigRun r = run_rig(sim, [&] {
    ASSERT_TRUE(sim.wait_for_rig(5.0));
    for (std::uint64_t k = 1; k <= 50; ++k) {
      sim.contact_point(2 * k);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    silent_from = steady_now();  // then the simulator dies without a word
  }, 0.3, 10.0);
  EXPECT_EQ(r.end, RigEnd::kContactTimeout) << r.message;
  EXPECT_GE(r.finished - silent_from, 0.3 - 0.01);  // (the last point arrived at most 10 ms before)
  EXPECT_LT(r.finished - silent_from, 5.0);
  EXPECT_NE(r.message.find("--timeout"), std::string::npos) << r.message;
}

TEST(UdpRigEnd, NoSimulatorStopsTheRigAfterItsConnectTimeout) {
  FakeSimulator sim;  // (bound, never answers)
  const RigRun r = run_rig(sim, [] {}, 0.3, 0.5);
  EXPECT_EQ(r.end, RigEnd::kConnectTimeout) << r.message;
  EXPECT_GE(r.seconds, 0.5);
  EXPECT_LT(r.seconds, 5.0);
  EXPECT_NE(r.message.find("--connect-timeout"), std::string::npos) << r.message;
}

// The interface files say what the code does: ContactPointArray's `mode` comment names every
// mode constant of the message, and those are the loop's modes; hil.launch's `rviz` argument
// describes rviz.
TEST(HilInterface, ModeCommentListsEveryModeConstant) {
  std::ifstream f(kDir + "/msg/ContactPointArray.msg");
  ASSERT_TRUE(f) << "msg/ContactPointArray.msg";
  std::string line, mode_comment;
  std::vector<std::pair<std::string, int>> constants;
  const std::regex constant(R"(^uint8\s+([A-Z_]+)\s*=\s*(\d+))"), field(R"(^uint8\s+mode\s*#(.*)$)");
  std::smatch m;
  while (std::getline(f, line)) {
    if (std::regex_search(line, m, constant)) constants.emplace_back(m[1], std::stoi(m[2]));
    else if (std::regex_search(line, m, field)) mode_comment = m[1];
  }
  ASSERT_FALSE(mode_comment.empty());
  ASSERT_EQ(constants.size(), 5u);
  for (const auto& [name, value] : constants) {
    EXPECT_NE(mode_comment.find(name), std::string::npos) << name << " not in the mode comment:" << mode_comment;
    std::string words = name;  // SAFE_HOLD -> "safe hold", as the loop names its modes
    for (char& c : words) c = c == '_' ? ' ' : static_cast<char>(std::tolower(c));
    EXPECT_EQ(words, mode_name(static_cast<Mode>(value))) << name << " = " << value;
  }
}

TEST(HilInterface, LaunchRvizArgumentDescribesRviz) {
  std::ifstream f(kDir + "/launch/hil.launch");
  std::stringstream s;
  s << f.rdbuf();
  std::smatch m;
  const std::string text = s.str();
  ASSERT_TRUE(std::regex_search(text, m, std::regex(R"re(<arg name="rviz"[^>]*doc="([^"]*)")re"))) << "no rviz argument";
  EXPECT_NE(std::string(m[1]).find("rviz"), std::string::npos) << m[1];
  EXPECT_EQ(std::string(m[1]).find("private parameters"), std::string::npos) << m[1];
}
