// Hardware in the loop over UDP, without ROS: the loop (hil::HilLoop, the same as the ROS node's)
// exchanging the fixed packets of udp_packets.h with a rig controller, and a simulated rig
// (UdpVirtualRig: the scene's lumped pantograph, as virtual_rig) that closes the loop over UDP.
//
// The simulator binds a UDP port; every valid measurement that is newer than the ones before
// (sequence numbers) is handed to the loop, which answers each period with a contact point sent
// to the rig's address (given, or the source of the newest valid measurement). Bad packets are
// counted per reason and rejected whole; lost, reordered and duplicated ones are counted.
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
#include <string>

#include <nlohmann/json.hpp>

#include "catenary_sim/core/scene.hpp"
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
  std::uint64_t packets_lost = 0, packets_reordered = 0, packets_duplicated = 0;
  double latency_p99 = 0.0, jitter_p50 = 0.0, jitter_p99 = 0.0, jitter_max = 0.0, delay_energy = 0.0;
  std::array<std::uint64_t, 8> jitter_counts{};  // JitterSummary::counts
};
using MonitorRing = SpscRing<MonitorSample, 4096>;  // 4 s at 1 kHz

struct UdpLoopOptions {
  std::string bind_address = "0.0.0.0";
  int port = 47800;
  std::string rig_address;  // empty: answer the source of the newest valid measurement
  int rig_port = 0;
  bool same_clock = false;  // the rig's send_time_ns is on this machine's CLOCK_MONOTONIC: transport measured
};

class UdpLoopSkin : public LoopSkin {
 public:
  // Opens the socket (HilError naming --port/--bind/--rig on failure) and checks that the scene's
  // frames fit the packets. `running`: an extra condition (e.g. ros::ok); `log_sink` receives
  // the loop's lines (stderr by default).
  UdpLoopSkin(HilLoop& loop, const UdpLoopOptions& o, MonitorRing* monitor = nullptr);
  void set_log(std::function<void(LogLevel, const std::string&)> sink) { log_sink_ = std::move(sink); }
  void set_running(std::function<bool()> f) { running_fn_ = std::move(f); }
  void stop() { stop_ = true; }
  int port() const { return socket_.port(); }

  bool running() override { return !stop_ && (!running_fn_ || running_fn_()); }
  void receive(double until) override;
  void send(const PointFrame& frame) override;
  void log(LogLevel level, const std::string& text) override;
  void pass_ended(std::unique_ptr<PassRecorder> recorder, const State& state) override {
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
  // The packet figures as JSON fields of the report.
  void add_report(nlohmann::ordered_json& j) const;

 private:
  void take(const std::uint8_t* data, std::size_t n, const sockaddr_in& from, double arrival);

  HilLoop& loop_;
  UdpLoopOptions opt_;
  UdpSocket socket_;
  MonitorRing* monitor_ = nullptr;
  bool fixed_rig_ = false, have_rig_ = false;
  sockaddr_in rig_{};
  std::atomic<bool> stop_{false};
  std::function<bool()> running_fn_;
  std::function<void(LogLevel, const std::string&)> log_sink_;
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
  // Runs while `keep_running()` (and, with `until_ended`, until the simulator reports ENDED).
  int run(const std::function<bool()>& keep_running, bool until_ended = false);
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
  std::uint64_t sent_ = 0, missed_ = 0, rejected_ = 0;
  std::array<std::pair<std::uint64_t, double>, 256> sent_at_{};  // (step, steady s), a ring
  LatencyHistogram round_trip_;
  udp::SequenceTracker tracker_;
  std::function<void(const csim_udp_contact_point&)> observer_;
};

}  // namespace hil
}  // namespace catenary_sim
