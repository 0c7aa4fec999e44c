// Hardware in the loop over UDP, without ROS: the loop (hil::HilLoop, the same as the ROS node's)
// exchanging the fixed packets of udp_packets.h with a rig controller, and a simulated rig
// (UdpVirtualRig: the scene's lumped pantograph, as virtual_rig) that closes the loop over UDP.
//
// The simulator binds a UDP port and follows one rig: the source (address and port) of the first
// valid packet from an allowed sender (UdpLoopOptions::allow, and the --rig address if given).
// Every valid measurement of that rig that is newer than the ones before (sequence numbers) is
// handed to the loop, which answers each period with a contact point sent to the rig (--rig, or
// its source). Packets from other senders are counted (foreign; refused when not on the
// allow-list), logged at most once a second and ignored. A hello from the rig's address on a new
// port follows a restarted rig there; an ~arm after the end releases the rig. Bad packets are
// counted per reason and rejected whole; lost, reordered and duplicated ones are counted. When
// the pass ends, or at finish(), an end packet tells the rig to stop.
// Monitoring (ROS topics, a recorder) takes MonitorSamples from a lock-free SPSC ring on a thread
// of its own: sending them never blocks the loop (a full ring drops and counts).
#pragma once

#include <netinet/in.h>

#include <array>
#include <cmath>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "catenary_sim/core/scene/scene.hpp"
#include "catenary_sim/hil/loop.hpp"
#include "catenary_sim/hil/rig_pantograph.hpp"
#include "catenary_sim/hil/spsc_ring.hpp"
#include "catenary_sim/hil/udp_packets.hpp"

namespace catenary_sim {
namespace hil {

// A bound, non-blocking UDP socket. Throws HilError naming `name` (the option) when the address
// or port cannot be used.
class UdpSocket {
 public:
  UdpSocket(const std::string& address, int port, const std::string& name);
  ~UdpSocket();
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;
  int fd() const { return fd_; }
  int port() const;  // the bound port (useful with port 0)
  // Waits until readable or the steady clock reaches `until` (s). True when readable.
  bool wait_readable(double until) const;
  // One datagram (-1: none waiting), with its source.
  long receive(void* buf, std::size_t cap, sockaddr_in* from) const;
  bool send(const void* data, std::size_t n, const sockaddr_in& to) const;

 private:
  int fd_ = -1;
};
// Resolves a numeric IPv4 address; throws HilError naming `name`.
sockaddr_in udp_address(const std::string& address, int port, const std::string& name);
// "HOST:PORT" with a numeric IPv4 HOST and a port in [1, 65535]; throws HilError naming `name`,
// the value and what is allowed.
std::pair<std::string, int> parse_host_port(const std::string& text, const std::string& name);
// "A:P" as text.
std::string address_text(const sockaddr_in& a);

// One entry of the allow-list: a numeric IPv4 address, with a port or any (0).
struct AllowedSender {
  std::uint32_t address = 0;  // network byte order
  std::uint16_t port = 0;     // host byte order, 0: any
};
// "10.0.0.2" or "10.0.0.2:47801", several separated by commas (empty: none); throws HilError
// naming `name`, the entry and what is allowed.
std::vector<AllowedSender> parse_allow_list(const std::string& text, const std::string& name);
std::int64_t monotonic_ns();

// What the monitoring thread gets of each contact point (fixed size: it goes through the ring).
struct MonitorSample {
  double wall = 0.0;  // steady s when sent
  double simulation_time = 0.0, speed = 0.0;
  std::uint64_t step = 0, measurement_step = 0;
  std::uint32_t pass_count = 0, pantographs = 0;
  std::uint8_t mode = 0;
  std::array<double, CSIM_UDP_MAX_PANTOGRAPHS> position{}, height{}, velocity{}, path_velocity{}, applied_force{},
      measurement_age{};
  // The loop's figures at that period (copied: the monitoring thread never reads the loop's own).
  std::int64_t periods = 0, overruns = 0, held = 0, holds = 0, rejected = 0;
  std::uint64_t packets_lost = 0, packets_reordered = 0, packets_duplicated = 0, packets_foreign = 0,
                packets_refused = 0;
  double latency_p99 = 0.0, jitter_p50 = 0.0, jitter_p99 = 0.0, jitter_max = 0.0, delay_energy = 0.0;
  std::array<std::uint64_t, 8> jitter_counts{};  // JitterSummary::counts
};
using MonitorRing = SpscRing<MonitorSample, 4096>;  // 4 s at 1 kHz

struct UdpLoopOptions {
  std::string bind_address = "0.0.0.0";
  int port = 47800;
  std::string rig_address;  // empty: answer the rig's source; else only this address is the rig
  int rig_port = 0;
  std::vector<AllowedSender> allow;  // empty: any sender may become the rig
  bool same_clock = false;  // the rig's send_time_ns is on this machine's CLOCK_MONOTONIC: transport measured
  // How errors name the options: the command line's by default (a ROS node gives its parameters).
  std::string bind_name = "--bind/--port", rig_name = "--rig", allow_name = "--allow", scene_name = "--scene";
};

class UdpLoopSkin : public LoopSkin {
 public:
  // Opens the socket (HilError naming the option of UdpLoopOptions on failure) and checks that the scene's
  // frames fit the packets. `running`: an extra condition (e.g. ros::ok); `log_sink` receives
  // the loop's lines (stderr by default).
  UdpLoopSkin(HilLoop& loop, const UdpLoopOptions& o, MonitorRing* monitor = nullptr);
  void set_log(std::function<void(LogLevel, const std::string&)> sink) { log_sink_ = std::move(sink); }
  void set_running(std::function<bool()> f) { running_fn_ = std::move(f); }
  void stop() { stop_ = true; }
  int port() const { return socket_.port(); }
  // After the loop has returned: tells the rig that the pass ended (or, before its end, that the
  // simulator stops), unless an end packet for this pass was already sent.
  void finish();

  bool running() override { return !stop_ && (!running_fn_ || running_fn_()); }
  void receive(double until) override;
  void send(const PointFrame& frame) override;
  void log(LogLevel level, const std::string& text) override;
  // A pass has ended (loop thread): to `on_pass_ended` when set (it must not block the loop for
  // long), else kept for take_finished().
  void set_on_pass_ended(std::function<void(std::unique_ptr<PassRecorder>, const State&)> f) {
    on_pass_ended_ = std::move(f);
  }
  void pass_ended(std::unique_ptr<PassRecorder> recorder, const State& state) override {
    if (on_pass_ended_) {
      on_pass_ended_(std::move(recorder), state);
      return;
    }
    finished_ = std::move(recorder);
    finished_state_ = state;
  }
  // The recorder of the last pass that ended (null: none), with its final state.
  std::unique_ptr<PassRecorder> take_finished(State* state) {
    if (state) *state = finished_state_;
    return std::move(finished_);
  }

  const udp::SequenceTracker& sequence() const { return tracker_; }
  const std::array<std::uint64_t, static_cast<int>(udp::Reject::kNumReasons)>& rejected() const { return rejected_; }
  std::uint64_t sent() const { return sent_; }
  std::uint64_t send_errors() const { return send_errors_; }
  std::uint64_t unusable() const { return unusable_; }  // reordered or duplicated: dropped
  std::uint64_t foreign() const { return foreign_; }    // from another sender than the rig: ignored
  std::uint64_t refused() const { return refused_; }    // from a sender not on the allow-list
  std::uint64_t rig_moves() const { return rig_moves_; }  // the rig followed to a new port (hello)
  std::uint64_t ends_sent() const { return ends_sent_; }
  bool has_rig() const { return have_peer_; }
  const sockaddr_in& rig() const { return peer_; }
  // The packet figures as JSON fields of the report.
  void add_report(nlohmann::ordered_json& j) const;

 private:
  // A packet from `from`: refused off the allow-list, ignored from another sender than the rig,
  // rejected when it does not decode, else it names the rig (follow_rig), is checked against the
  // rig's numbering (in_sequence) and handed to the loop (hand_to_loop).
  void take(const std::uint8_t* data, std::size_t n, const sockaddr_in& from, double arrival);
  void ignore_foreign(const sockaddr_in& from, const std::string& why);
  // The sender of a valid packet: the rig (the first, or one saying hello from the rig's address);
  // false (counted as foreign) for another.
  bool follow_rig(const sockaddr_in& from, bool from_peer, const csim_udp_measurement& m);
  // False for a hello, a duplicate or one older than a measurement already taken.
  bool in_sequence(const sockaddr_in& from, const csim_udp_measurement& m);
  void hand_to_loop(const csim_udp_measurement& m, double arrival);
  bool allowed(const sockaddr_in& from) const;
  void send_end(std::uint32_t reason, const PointFrame* f);
  // Why the pass that ended did (CSIM_UDP_END_FINISHED, _DIVERGED or _DEWIRED).
  std::uint32_t end_reason() const;
  // At most once per second per `slot`: true when the line may be logged now.
  bool throttle(int slot);
  void say(LogLevel level, const std::string& text) { log(level, loop_.options().who + ": " + text); }

  HilLoop& loop_;
  UdpLoopOptions opt_;
  UdpSocket socket_;
  MonitorRing* monitor_ = nullptr;
  bool fixed_rig_ = false, have_rig_ = false;
  sockaddr_in rig_{};
  bool have_peer_ = false;  // the rig whose measurements are taken (address and port)
  sockaddr_in peer_{};
  std::uint64_t foreign_ = 0, refused_ = 0, rig_moves_ = 0, ends_sent_ = 0;
  std::uint32_t end_sent_pass_ = 0;
  bool end_sent_ = false;
  Mode last_mode_ = Mode::kWaiting;
  std::array<double, 4> throttle_until_{};
  std::atomic<bool> stop_{false};
  std::function<bool()> running_fn_;
  std::function<void(LogLevel, const std::string&)> log_sink_;
  std::function<void(std::unique_ptr<PassRecorder>, const State&)> on_pass_ended_;
  udp::SequenceTracker tracker_;
  std::array<std::uint64_t, static_cast<int>(udp::Reject::kNumReasons)> rejected_{};
  std::uint64_t sent_ = 0, send_errors_ = 0, unusable_ = 0;
  std::uint32_t sequence_ = 0, measurement_sequence_ = 0, in_effect_sequence_ = 0;
  std::int64_t last_overruns_ = 0, last_held_ = 0;
  alignas(8) std::uint8_t buf_[2048];
  csim_udp_contact_point packet_{};
  std::array<double, CSIM_UDP_MAX_PANTOGRAPHS> force_{};
  std::unique_ptr<PassRecorder> finished_;
  State finished_state_;
};

// A simulated rig over UDP: the lumped pantographs of `pantograph_scene` (the i-th lumped one for
// the i-th external pantograph, or by name with `names`), stepped up to each contact point
// against the previous one's wire (extrapolated along its path velocity), sending the contact
// force on its own clock at `rate` (0: the simulator's loop rate, from the packets).
struct UdpRigOptions {
  std::string simulator_address = "127.0.0.1";
  int simulator_port = 47800;
  std::string bind_address = "0.0.0.0";
  int port = 0;  // 0: any
  double rate = 0.0;
  bool extrapolate = true;
  // s without a contact point, once one came, after which the rig stops (the simulator died or
  // the link broke); 0: never.
  double contact_timeout = 2.0;
  // s to wait for the first contact point (hellos every 50 ms meanwhile); 0: for ever.
  double connect_timeout = 30.0;
  // How errors name the options: the command line's by default (a ROS node gives its parameters).
  std::string bind_name = "--bind/--port", simulator_name = "--simulator", scene_name = "--pantograph-scene",
              rate_name = "--rate";
};

// How UdpVirtualRig::run ended.
enum class RigEnd {
  kStopped,         // keep_running() turned false
  kEnded,           // the simulator reported the end (an end packet, or ENDED with until_ended)
  kContactTimeout,  // no contact point for contact_timeout
  kConnectTimeout,  // no first contact point within connect_timeout
  kCannotServe      // the simulator has more external pantographs than the scene lumped ones
};

// A rig's next measurement tick: `next` moved on by `period`; when the rig is late by more than a
// period (`now`, s on the same clock, beyond it) it skips the ticks it missed, counting them in
// `missed`, rather than sending them in a burst (UdpVirtualRig, and the ROS virtual_rig).
inline double next_rig_tick(double next, double period, double now, std::uint64_t& missed) {
  next += period;
  if (now > next) {
    ++missed;
    next += std::ceil((now - next) / period) * period;
  }
  return next;
}

class UdpVirtualRig {
 public:
  UdpVirtualRig(const Scene& pantograph_scene, const UdpRigOptions& o);
  // Runs while `keep_running()`, until the simulator sends an end packet (with `until_ended`
  // also until a contact point says ENDED; without it an end packet of a pass that ended is
  // noted and the rig keeps running for a new pass, one of a simulator that stops still ends it),
  // or until a timeout of UdpRigOptions. message() says why it returned.
  RigEnd run(const std::function<bool()>& keep_running, bool until_ended = false);
  const std::string& message() const { return message_; }
  std::uint64_t foreign() const { return foreign_; }  // datagrams from another source than the simulator
  const udp::SequenceTracker& sequence() const { return tracker_; }
  std::uint64_t sent() const { return sent_; }
  std::uint64_t missed_ticks() const { return missed_; }
  std::uint64_t rejected() const { return rejected_; }
  const LatencyHistogram& round_trip() const { return round_trip_; }
  int port() const { return socket_.port(); }
  // Called for every contact point taken (tests record them).
  void set_observer(std::function<void(const csim_udp_contact_point&)> f) { observer_ = std::move(f); }

 private:
  void on_point(const csim_udp_contact_point& p);
  void send_measurement();
  // Takes every packet waiting from the simulator: contact points (on_point) and end packets.
  void drain();
  // Why run() returns now (an end, a rig that cannot serve, !keep_running), or nothing.
  std::optional<RigEnd> over(const std::function<bool()>& keep_running, bool until_ended);
  // Says hello until the first contact point; a reason to return from run(), or nothing once connected.
  std::optional<RigEnd> connect(const std::function<bool()>& keep_running, bool until_ended);

  Scene scene_;
  UdpRigOptions opt_;
  UdpSocket socket_;
  sockaddr_in simulator_{};
  std::vector<RigPantograph> rigs_;  // the scene's lumped pantographs, in order
  RigStepper stepper_;
  bool have_ = false, ended_ = false;
  std::uint32_t sequence_ = 0;
  std::uint64_t step_ = 0;
  double dt_ = 0.0;
  std::uint32_t steps_per_period_ = 1;
  std::uint64_t sent_ = 0, missed_ = 0, rejected_ = 0, foreign_ = 0;
  bool end_received_ = false, cannot_serve_ = false;
  std::uint32_t end_reason_ = 0;
  double last_point_ = 0.0;  // steady s of the newest contact point taken
  std::string message_;
  std::array<std::pair<std::uint64_t, double>, 256> sent_at_{};  // (step, steady s), a ring
  LatencyHistogram round_trip_;
  udp::SequenceTracker tracker_;
  std::function<void(const csim_udp_contact_point&)> observer_;
};

}  // namespace hil
}  // namespace catenary_sim
