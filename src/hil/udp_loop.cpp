#include "catenary_sim/hil/udp_loop.hpp"

#include "../core/util/format.hpp"  // the core's numbers in messages: one way for all

#include <arpa/inet.h>
#include <poll.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>

#include <nlohmann/json.hpp>

namespace catenary_sim {
namespace hil {

std::int64_t monotonic_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

sockaddr_in udp_address(const std::string& address, int port, const std::string& name) {
  if (port < 0 || port > 65535)
    throw HilError(name + " port = " + std::to_string(port) + " rejected: allowed 0 to 65535");
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  if (inet_pton(AF_INET, address.c_str(), &a.sin_addr) != 1)
    throw HilError(name + " = '" + address + "' rejected: allowed a numeric IPv4 address, e.g. 127.0.0.1 or 0.0.0.0");
  return a;
}

std::pair<std::string, int> parse_host_port(const std::string& text, const std::string& name) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == text.size())
    throw HilError(name + " = '" + text + "' rejected: allowed HOST:PORT with a numeric IPv4 HOST and a port 1 to "
                   "65535, e.g. 127.0.0.1:47801");
  const std::string host = text.substr(0, colon), digits = text.substr(colon + 1);
  int port = -1;
  if (digits.size() <= 5 && digits.find_first_not_of("0123456789") == std::string::npos) port = std::stoi(digits);
  if (port < 1 || port > 65535)
    throw HilError(name + " = '" + text + "' rejected: the port '" + digits + "' is not allowed: allowed 1 to 65535");
  in_addr a{};
  if (inet_pton(AF_INET, host.c_str(), &a) != 1)
    throw HilError(name + " = '" + text + "' rejected: the host '" + host +
                   "' is not allowed: allowed a numeric IPv4 address, e.g. 127.0.0.1 (no names, no IPv6)");
  const std::uint32_t h = ntohl(a.s_addr);
  if (h == INADDR_ANY || h == INADDR_BROADCAST || (h >> 28) == 0xE)
    throw HilError(name + " = '" + text + "' rejected: the host '" + host +
                   "' is not one machine: allowed a unicast IPv4 address (not 0.0.0.0, broadcast or multicast)");
  return {host, port};
}

std::string address_text(const sockaddr_in& a) {
  char b[INET_ADDRSTRLEN] = "?";
  inet_ntop(AF_INET, &a.sin_addr, b, sizeof b);
  return std::string(b) + ":" + std::to_string(ntohs(a.sin_port));
}

std::vector<AllowedSender> parse_allow_list(const std::string& text, const std::string& name) {
  std::vector<AllowedSender> out;
  std::size_t i = 0;
  while (i <= text.size() && !text.empty()) {
    const std::size_t comma = std::min(text.find(',', i), text.size());
    const std::string entry = text.substr(i, comma - i);
    AllowedSender s;
    const auto colon = entry.find(':');
    std::string host = entry;
    bool ok = !entry.empty();
    if (ok && colon != std::string::npos) {
      host = entry.substr(0, colon);
      const std::string digits = entry.substr(colon + 1);
      ok = !digits.empty() && digits.size() <= 5 && digits.find_first_not_of("0123456789") == std::string::npos;
      const int port = ok ? std::stoi(digits) : 0;
      ok = ok && port >= 1 && port <= 65535;
      s.port = static_cast<std::uint16_t>(port);
    }
    in_addr a{};
    if (!ok || inet_pton(AF_INET, host.c_str(), &a) != 1)
      throw HilError(name + " entry '" + entry + "' rejected: allowed a numeric IPv4 address with an optional port "
                     "1 to 65535 (10.0.0.2 or 10.0.0.2:47801), several separated by commas");
    s.address = a.s_addr;
    out.push_back(s);
    i = comma + 1;
  }
  return out;
}

UdpSocket::UdpSocket(const std::string& address, int port, const std::string& name) {
  const sockaddr_in a = udp_address(address, port, name);
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw HilError(name + ": no UDP socket: " + std::strerror(errno));
  // Room for a stall of the loop (a second at 10 kHz of ~100-byte measurements).
  const int rcv = 1 << 20;
  setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcv, sizeof rcv);
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    const int err = errno;
    ::close(fd_);
    fd_ = -1;
    throw HilError(name + " = " + address + ":" + std::to_string(port) + ": cannot bind: " + std::strerror(err) +
                   (err == EADDRINUSE ? " (another process uses the port: choose another)" : ""));
  }
}

UdpSocket::~UdpSocket() {
  if (fd_ >= 0) ::close(fd_);
}

int UdpSocket::port() const {
  sockaddr_in a{};
  socklen_t n = sizeof a;
  if (getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &n) != 0) return -1;
  return ntohs(a.sin_port);
}

bool UdpSocket::wait_readable(double until) const {
  const double left = until - steady_now();
  pollfd p{fd_, POLLIN, 0};
  timespec ts{};
  if (left > 0.0) {
    ts.tv_sec = static_cast<time_t>(left);
    ts.tv_nsec = static_cast<long>((left - static_cast<double>(ts.tv_sec)) * 1e9);
  }
  return ppoll(&p, 1, &ts, nullptr) > 0 && (p.revents & POLLIN);
}

long UdpSocket::receive(void* buf, std::size_t cap, sockaddr_in* from) const {
  socklen_t n = sizeof(sockaddr_in);
  const ssize_t r = ::recvfrom(fd_, buf, cap, MSG_DONTWAIT, reinterpret_cast<sockaddr*>(from), &n);
  return r < 0 ? -1 : static_cast<long>(r);
}

bool UdpSocket::send(const void* data, std::size_t n, const sockaddr_in& to) const {
  return ::sendto(fd_, data, n, MSG_DONTWAIT, reinterpret_cast<const sockaddr*>(&to), sizeof to) ==
         static_cast<ssize_t>(n);
}

// ---- The simulator's side ----

UdpLoopSkin::UdpLoopSkin(HilLoop& loop, const UdpLoopOptions& o, MonitorRing* monitor)
    : loop_(loop), opt_(o), socket_(o.bind_address, o.port, o.bind_name), monitor_(monitor) {
  if (const std::string e = udp::check_fits(loop.model()); !e.empty()) throw HilError(o.scene_name + ": " + e);
  if (!o.rig_address.empty()) {
    if (o.rig_port <= 0 || o.rig_port > 65535)
      throw HilError(o.rig_name + " port = " + std::to_string(o.rig_port) + " rejected: allowed 1 to 65535");
    rig_ = udp_address(o.rig_address, o.rig_port, o.rig_name);
    fixed_rig_ = have_rig_ = true;
    if (!allowed(rig_))
      throw HilError(o.rig_name + " = " + address_text(rig_) + " is not on the allow-list (" + o.allow_name +
                     "): it could never be the rig");
  }
  loop_.attach(this);
}

bool UdpLoopSkin::throttle(int slot) {
  const double now = steady_now();
  if (now < throttle_until_[slot]) return false;
  throttle_until_[slot] = now + 1.0;
  return true;
}

bool UdpLoopSkin::allowed(const sockaddr_in& from) const {
  if (opt_.allow.empty()) return true;
  for (const AllowedSender& a : opt_.allow)
    if (a.address == from.sin_addr.s_addr && (a.port == 0 || a.port == ntohs(from.sin_port))) return true;
  return false;
}

void UdpLoopSkin::log(LogLevel level, const std::string& text) {
  if (log_sink_) {
    log_sink_(level, text);
    return;
  }
  std::fprintf(stderr, "[%s] %s\n", level == LogLevel::kInfo ? "INFO" : level == LogLevel::kWarn ? "WARN" : "ERROR",
               text.c_str());
}

void UdpLoopSkin::receive(double until) {
  while (true) {
    sockaddr_in from{};
    const long n = socket_.receive(buf_, sizeof buf_, &from);
    if (n >= 0) {
      take(buf_, static_cast<std::size_t>(n), from, steady_now());
      continue;  // (all that are waiting: only the newest is used)
    }
    if (loop_.fresh() || steady_now() >= until || !running()) return;
    socket_.wait_readable(until);
    if (steady_now() >= until && !socket_.wait_readable(0.0)) return;
  }
}

namespace {
// Throttle slots of UdpLoopSkin's log lines about the packets it takes.
enum { kSlotForeign, kSlotRefused, kSlotUnusable };
}  // namespace

void UdpLoopSkin::take(const std::uint8_t* data, std::size_t n, const sockaddr_in& from, double arrival) {
  if (!allowed(from)) {
    ++refused_;
    if (throttle(kSlotRefused))
      say(LogLevel::kWarn, "UDP packet from " + address_text(from) + " refused: not on the allow-list (" +
                               std::to_string(refused_) + " refused so far)");
    return;
  }
  const bool same_address = have_peer_ ? from.sin_addr.s_addr == peer_.sin_addr.s_addr
                                       : !fixed_rig_ || from.sin_addr.s_addr == rig_.sin_addr.s_addr;
  const bool from_peer = have_peer_ && same_address && from.sin_port == peer_.sin_port;
  if (!same_address) {
    ignore_foreign(from, have_peer_ ? "the loop follows the rig at " + address_text(peer_)
                                    : "only the rig at --rig " + address_text(rig_) + " may send");
    return;
  }
  csim_udp_measurement m;
  udp::Reject why;
  std::string reason;
  if (!udp::decode_measurement(data, n, static_cast<std::uint32_t>(loop_.external().size()), m, why, reason)) {
    if (have_peer_ && !from_peer) {
      ignore_foreign(from, "the loop follows the rig at " + address_text(peer_));
      return;
    }
    ++rejected_[static_cast<int>(why)];
    tracker_.rejected();
    loop_.reject("UDP " + reason);
    return;
  }
  // Values the loop would refuse are refused before the packet names the rig or its number is
  // taken: a refused packet leaves both as they were (a number taken from it would drop every
  // later valid measurement numbered below it).
  if (m.pantographs > 0) {
    for (std::uint32_t i = 0; i < m.pantographs; ++i) force_[i] = m.force[i];  // (out of the packed struct)
    if (std::string e = loop_.measurement_error(force_.data(), m.pantographs, "UDP measurement.force", true);
        !e.empty()) {
      if (have_peer_ && !from_peer) {
        ignore_foreign(from, "the loop follows the rig at " + address_text(peer_));
        return;
      }
      tracker_.rejected();
      loop_.reject(e);
      return;
    }
  }
  if (!follow_rig(from, from_peer, m)) return;
  if (!in_sequence(from, m)) return;
  hand_to_loop(m, arrival);
}

void UdpLoopSkin::ignore_foreign(const sockaddr_in& from, const std::string& why) {
  ++foreign_;
  if (throttle(kSlotForeign))
    say(LogLevel::kWarn, "UDP packet from " + address_text(from) + " ignored: " + why + " (" +
                             std::to_string(foreign_) + " foreign packets so far)");
}

bool UdpLoopSkin::follow_rig(const sockaddr_in& from, bool from_peer, const csim_udp_measurement& m) {
  const bool hello = m.pantographs == 0;
  if (!have_peer_ || (!from_peer && hello)) {
    // The rig: the first valid sender, or the rig's own address on a new port saying hello (a
    // restarted controller with a new socket). Its numbering starts again.
    if (have_peer_) {
      ++rig_moves_;
      say(LogLevel::kWarn, "UDP rig moved from " + address_text(peer_) + " to " + address_text(from) +
                               " (a hello from the rig's address: a restarted rig)");
      tracker_.restart();
    } else {
      say(LogLevel::kInfo, "UDP rig at " + address_text(from) + (hello ? " (hello)" : ""));
    }
    peer_ = from;
    have_peer_ = true;
  } else if (!from_peer) {
    ignore_foreign(from, "the loop follows the rig at " + address_text(peer_) + "; a restarted rig says hello first");
    return false;
  } else if (hello && tracker_.behind(m.header.sequence)) {
    tracker_.restart();  // a hello numbered below what the rig sent before: it started numbering again
  }
  if (!fixed_rig_) {
    rig_ = from;
    have_rig_ = true;
  }
  return true;
}

bool UdpLoopSkin::in_sequence(const sockaddr_in& from, const csim_udp_measurement& m) {
  const auto verdict = tracker_.observe(m.header.sequence);
  if (m.pantographs == 0) return false;  // a hello: the rig's address, no measurement
  if (!udp::SequenceTracker::usable(verdict)) {
    ++unusable_;  // older than one already taken (reordered) or a duplicate: counted, not used
    if (throttle(kSlotUnusable))
      say(LogLevel::kWarn, "UDP measurement " + std::to_string(m.header.sequence) + " from the rig ignored: " +
                               (verdict == udp::SequenceTracker::Verdict::kDuplicate ? "a duplicate" : "older than ") +
                               (verdict == udp::SequenceTracker::Verdict::kDuplicate
                                    ? std::string()
                                    : std::to_string(tracker_.newest()) + ", already taken") +
                               " (" + std::to_string(unusable_) + " reordered or duplicated so far; " +
                               std::to_string(udp::SequenceTracker::kResyncRun) +
                               " in a row from lower numbers are taken as a restart)");
    return false;
  }
  if (verdict == udp::SequenceTracker::Verdict::kRestart)
    say(LogLevel::kWarn, "UDP rig " + address_text(from) + " numbers its packets again from " +
                             std::to_string(m.header.sequence) + ": followed");
  return true;
}

void UdpLoopSkin::hand_to_loop(const csim_udp_measurement& m, double arrival) {
  for (std::uint32_t i = 0; i < m.pantographs; ++i) force_[i] = m.force[i];
  const double measured = m.measured_time_ns > 0 ? 1e-9 * static_cast<double>(m.measured_time_ns) : 0.0;
  if (!loop_.accept(force_.data(), m.pantographs, arrival, measured, m.answers_step, "UDP measurement.force", true))
    return;
  measurement_sequence_ = m.header.sequence;
  if (opt_.same_clock && m.header.send_time_ns > 0) {
    const double transport = arrival - 1e-9 * static_cast<double>(m.header.send_time_ns);
    if (transport >= 0.0 && transport < 1.0) loop_.add_transport(transport);
  }
}

void UdpLoopSkin::send_end(std::uint32_t reason, const PointFrame* f) {
  end_sent_ = true;
  end_sent_pass_ = loop_.pass_count();
  if (!have_rig_) return;
  csim_udp_end e;
  std::memset(&e, 0, sizeof e);
  // (the step at the end: the frame's, or the state's when the loop has returned without one)
  e.step = f ? f->step : static_cast<std::uint64_t>(loop_.state().steps);
  e.pass_count = loop_.pass_count();
  e.reason = reason;
  e.simulation_time = loop_.state().time;
  // Three copies: a rig that loses one still stops at once rather than after its own timeout.
  for (int i = 0; i < 3; ++i) {
    udp::fill_header(e.header, CSIM_UDP_KIND_END, CSIM_UDP_END_SIZE, ++sequence_, monotonic_ns());
    if (socket_.send(&e, sizeof e, rig_)) ++ends_sent_;
    else ++send_errors_;
  }
  say(LogLevel::kInfo, std::string("UDP end sent to the rig at ") + address_text(rig_) + ": " +
                           udp::end_reason_name(reason));
}

std::uint32_t UdpLoopSkin::end_reason() const {
  return loop_.diverged() ? CSIM_UDP_END_DIVERGED : loop_.dewired() ? CSIM_UDP_END_DEWIRED : CSIM_UDP_END_FINISHED;
}

void UdpLoopSkin::finish() {
  if (end_sent_ && end_sent_pass_ == loop_.pass_count()) return;
  send_end(loop_.mode() == Mode::kEnded ? end_reason() : CSIM_UDP_END_SHUTDOWN, nullptr);
}

void UdpLoopSkin::send(const PointFrame& f) {
  // Which measurement the period used: the newest accepted while running (the loop applies the
  // newest), none otherwise (waiting, safe hold, paused, ended).
  in_effect_sequence_ = loop_.mode() == Mode::kRunning ? measurement_sequence_ : 0;
  std::uint32_t flags = 0;
  const LoopCounters& c = loop_.counters();
  if (c.held != last_held_) flags |= CSIM_UDP_FLAG_HELD;
  if (c.overruns != last_overruns_) flags |= CSIM_UDP_FLAG_OVERRUN;
  last_held_ = c.held;
  last_overruns_ = c.overruns;
  if (loop_.options().delay_compensation > 0.0) flags |= CSIM_UDP_FLAG_COMPENSATED;
  if (last_mode_ == Mode::kEnded && f.mode == Mode::kWaiting) {
    // ~arm after the end: the next pass takes the first allowed sender as its rig.
    if (have_peer_) say(LogLevel::kInfo, "UDP rig " + address_text(peer_) + " released (~arm): the next sender is the rig");
    have_peer_ = false;
    end_sent_ = false;
    tracker_.restart(false);
    if (!fixed_rig_) have_rig_ = false;
  }
  last_mode_ = f.mode;
  if (have_rig_) {
    udp::encode_contact_point(f, ++sequence_, monotonic_ns(), in_effect_sequence_, flags, packet_);  // (fits: checked)
    if (socket_.send(&packet_, sizeof packet_, rig_)) ++sent_;
    else ++send_errors_;
  }
  if (f.mode == Mode::kEnded && !(end_sent_ && end_sent_pass_ == f.pass_count))
    send_end(end_reason(), &f);
  if (monitor_) {
    MonitorSample s;
    s.wall = steady_now();
    s.simulation_time = f.simulation_time;
    s.speed = f.speed;
    s.step = f.step;
    s.measurement_step = f.measurement_step;
    s.pass_count = f.pass_count;
    s.mode = static_cast<std::uint8_t>(f.mode);
    s.pantographs = static_cast<std::uint32_t>(std::min<std::size_t>(f.pantographs.size(), CSIM_UDP_MAX_PANTOGRAPHS));
    for (std::uint32_t i = 0; i < s.pantographs; ++i) {
      const PantographPoint& p = f.pantographs[i];
      s.position[i] = p.position;
      s.height[i] = p.height;
      s.velocity[i] = p.velocity;
      s.path_velocity[i] = p.path_velocity;
      s.applied_force[i] = p.applied_force;
      s.measurement_age[i] = p.measurement_age;
    }
    s.periods = c.batches;
    s.overruns = c.overruns;
    s.held = c.held;
    s.holds = c.holds;
    s.rejected = c.rejected;
    s.packets_lost = tracker_.lost();
    s.packets_reordered = tracker_.reordered();
    s.packets_duplicated = tracker_.duplicates();
    s.packets_foreign = foreign_;
    s.packets_refused = refused_;
    s.latency_p99 = loop_.latency_quantiles()[1];
    s.jitter_p50 = loop_.jitter_summary().p50;
    s.jitter_p99 = loop_.jitter_summary().p99;
    s.jitter_max = loop_.jitter_summary().max;
    s.jitter_counts = loop_.jitter_summary().counts;
    s.delay_energy = loop_.energy().delay_j;
    monitor_->push(s);  // (never waits: a full ring drops and counts)
  }
}

void UdpLoopSkin::add_report(nlohmann::ordered_json& j) const {
  nlohmann::ordered_json u;
  u["port"] = socket_.port();
  u["packets_received"] = tracker_.received();
  u["packets_lost"] = tracker_.lost();
  u["packets_reordered"] = tracker_.reordered();
  u["packets_duplicated"] = tracker_.duplicates();
  u["sender_restarts"] = tracker_.restarts();
  nlohmann::ordered_json r;
  for (int i = 0; i < static_cast<int>(udp::Reject::kNumReasons); ++i)
    r[udp::reject_name(static_cast<udp::Reject>(i))] = rejected_[i];
  u["packets_rejected"] = r;
  u["packets_foreign"] = foreign_;
  u["packets_refused"] = refused_;
  u["rig_moves"] = rig_moves_;
  if (have_peer_) u["rig"] = address_text(peer_);
  u["contact_points_sent"] = sent_;
  u["ends_sent"] = ends_sent_;
  u["send_errors"] = send_errors_;
  if (monitor_) u["monitor_dropped"] = monitor_->dropped();
  j["udp"] = u;
}

// ---- The simulated rig ----

UdpVirtualRig::UdpVirtualRig(const Scene& scene, const UdpRigOptions& o)
    : scene_(scene), opt_(o), socket_(o.bind_address, o.port, o.bind_name), stepper_(o.extrapolate) {
  simulator_ = udp_address(o.simulator_address, o.simulator_port, o.simulator_name);
  if (!std::isfinite(o.rate) || !(o.rate == 0.0 || (o.rate >= 1.0 && o.rate <= 20000.0)))
    throw HilError(o.rate_name + " = " + fmt(o.rate) + " rejected: allowed 0 (the simulator's loop rate) or [1, 20000] Hz");
  if (!std::isfinite(o.contact_timeout) || o.contact_timeout < 0.0 || o.contact_timeout > 3600.0)
    throw HilError("--timeout = " + fmt(o.contact_timeout) + " rejected: allowed 0 (never) or up to 3600 s");
  if (!std::isfinite(o.connect_timeout) || o.connect_timeout < 0.0 || o.connect_timeout > 3600.0)
    throw HilError("--connect-timeout = " + fmt(o.connect_timeout) +
                   " rejected: allowed 0 (wait for ever) or up to 3600 s");
  for (const PantographSpec& ps : scene_.pantographs) {
    if (ps.moving_force || ps.external || ps.masses.empty()) continue;
    try {
      rigs_.emplace_back(ps, scene_.contact.stiffness);
    } catch (const std::invalid_argument& e) {
      throw HilError(o.scene_name + ": " + e.what());
    }
  }
  if (rigs_.empty()) throw HilError(o.scene_name + ": no lumped pantograph (type lumped) in the scene");
  if (rigs_.size() > CSIM_UDP_MAX_PANTOGRAPHS)  // (a packet carries no more)
    rigs_.erase(rigs_.begin() + CSIM_UDP_MAX_PANTOGRAPHS, rigs_.end());
}

void UdpVirtualRig::on_point(const csim_udp_contact_point& msg) {
  if (!(msg.dt > 0.0 && msg.dt < 1.0) || msg.steps_per_period == 0) return;
  if (msg.pantographs > rigs_.size()) {
    ++rejected_;
    if (!cannot_serve_)
      message_ = "the simulator has " + std::to_string(msg.pantographs) + " external pantographs; " + opt_.scene_name +
                 " has " + std::to_string(rigs_.size()) + " lumped one(s): allowed a scene with at least one lumped "
                 "pantograph per external one, in scene order";
    cannot_serve_ = true;
    return;
  }
  last_point_ = steady_now();
  if (observer_) observer_(msg);
  ended_ = (msg.state_flags & CSIM_UDP_MODE_MASK) == CSIM_UDP_MODE_ENDED;
  auto points_of = [](const csim_udp_pantograph_point& p) {
    std::vector<WirePoint> w(p.wire_points);
    for (std::uint32_t k = 0; k < p.wire_points; ++k) {
      w[k].on_wire = p.on_wire[k] != 0;
      w[k].height = p.wire_height[k];
      w[k].path_velocity = p.wire_path_velocity[k];
    }
    return w;
  };
  std::vector<std::vector<WirePoint>> points;
  for (std::uint32_t i = 0; i < msg.pantographs; ++i) points.push_back(points_of(msg.pantograph[i]));
  if (stepper_.needs_restart(msg.pass_count, msg.step, msg.pantographs))
    stepper_.restart(std::vector<RigPantograph>(rigs_.begin(), rigs_.begin() + msg.pantographs), std::move(points),
                     msg.pass_count, msg.step, msg.dt, msg.speed);
  else
    stepper_.advance(msg.step, points, msg.dt, msg.speed);
  have_ = true;
  step_ = msg.step;
  dt_ = msg.dt;
  steps_per_period_ = msg.steps_per_period;
  if (msg.measurement_step > 0) {
    auto& slot = sent_at_[msg.measurement_step % sent_at_.size()];
    if (slot.first == msg.measurement_step && slot.second > 0.0) {
      round_trip_.add(steady_now() - slot.second);
      slot.second = 0.0;
    }
  }
}

void UdpVirtualRig::send_measurement() {
  if (!have_) return;
  csim_udp_measurement m;
  std::memset(&m, 0, sizeof m);
  const std::int64_t now = monotonic_ns();
  udp::fill_header(m.header, CSIM_UDP_KIND_MEASUREMENT, CSIM_UDP_MEASUREMENT_SIZE, ++sequence_, now);
  m.answers_step = step_;
  m.measured_time_ns = now;
  m.pantographs = static_cast<std::uint32_t>(stepper_.size());
  for (std::size_t i = 0; i < stepper_.size(); ++i) m.force[i] = stepper_.force(i);
  // (no head acceleration: the field is optional, flags 0)
  if (socket_.send(&m, sizeof m, simulator_)) {
    ++sent_;
    auto& slot = sent_at_[step_ % sent_at_.size()];
    if (slot.first != step_) slot = {step_, steady_now()};  // (a repeated step keeps its first time)
  }
}

void UdpVirtualRig::drain() {
  alignas(8) std::uint8_t buf[2048];
  csim_udp_contact_point p;
  csim_udp_end e;
  const bool any_source = simulator_.sin_addr.s_addr == htonl(INADDR_ANY);
  sockaddr_in from{};
  long n;
  while ((n = socket_.receive(buf, sizeof buf, &from)) >= 0) {
    // Only the simulator's packets (a stray sender must not move the rig's actuator).
    if (from.sin_port != simulator_.sin_port || (!any_source && from.sin_addr.s_addr != simulator_.sin_addr.s_addr)) {
      ++foreign_;
      continue;
    }
    udp::Reject why;
    std::string reason;
    if (udp::kind_of(buf, static_cast<std::size_t>(n)) == CSIM_UDP_KIND_END) {
      if (!udp::decode_end(buf, static_cast<std::size_t>(n), e, why, reason)) {
        ++rejected_;
        continue;
      }
      if (!end_received_ || end_reason_ != e.reason)
        message_ = std::string("the simulator sent the end of pass ") + std::to_string(e.pass_count) + ": " +
                   udp::end_reason_name(e.reason);
      end_received_ = true;
      end_reason_ = e.reason;
      continue;
    }
    if (!udp::decode_contact_point(buf, static_cast<std::size_t>(n), p, why, reason)) {
      ++rejected_;
      continue;
    }
    if (!udp::SequenceTracker::usable(tracker_.observe(p.header.sequence))) continue;
    on_point(p);
  }
}

std::optional<RigEnd> UdpVirtualRig::over(const std::function<bool()>& keep_running, bool until_ended) {
  // The simulator ends the rig's run with an end packet: always when it stops, for a pass that
  // ended only with `until_ended` (else the rig waits for the next pass).
  if (cannot_serve_) return RigEnd::kCannotServe;
  if (end_received_ && (until_ended || end_reason_ == CSIM_UDP_END_SHUTDOWN)) return RigEnd::kEnded;
  if (until_ended && ended_) {
    if (message_.empty()) message_ = "the simulator reports the pass ENDED";
    return RigEnd::kEnded;
  }
  if (!keep_running()) return RigEnd::kStopped;
  return std::nullopt;
}

std::optional<RigEnd> UdpVirtualRig::connect(const std::function<bool()>& keep_running, bool until_ended) {
  // Until the first contact point: a hello every 50 ms (a measurement of no pantographs), from
  // which the simulator learns where to send (unless it was given --rig).
  const double started = steady_now();
  while (!have_) {
    if (auto r = over(keep_running, until_ended)) return r;
    if (opt_.connect_timeout > 0.0 && steady_now() - started > opt_.connect_timeout) {
      message_ = "no contact point from the simulator at " + address_text(simulator_) + " within --connect-timeout = " +
                 fmt(opt_.connect_timeout) + " s (is it running, on that address and port?)";
      return RigEnd::kConnectTimeout;
    }
    csim_udp_measurement hello;
    std::memset(&hello, 0, sizeof hello);
    udp::fill_header(hello.header, CSIM_UDP_KIND_MEASUREMENT, CSIM_UDP_MEASUREMENT_SIZE, ++sequence_, monotonic_ns());
    socket_.send(&hello, sizeof hello, simulator_);
    socket_.wait_readable(steady_now() + 0.05);
    drain();
  }
  return std::nullopt;
}

RigEnd UdpVirtualRig::run(const std::function<bool()>& keep_running, bool until_ended) {
  if (auto r = connect(keep_running, until_ended)) return *r;
  const double period0 = dt_ * steps_per_period_;
  const double period = opt_.rate > 0.0 ? 1.0 / opt_.rate : period0;
  double next = steady_now() + 0.25 * period;
  while (true) {
    if (auto r = over(keep_running, until_ended)) return *r;
    if (opt_.contact_timeout > 0.0 && steady_now() - last_point_ > opt_.contact_timeout) {
      message_ = "no contact point from the simulator for --timeout = " + fmt(opt_.contact_timeout) +
                 " s: the simulator stopped or the link broke";
      return RigEnd::kContactTimeout;
    }
    // Take contact points as they come (stepping the pantograph up to each at once) until the
    // tick, then send the contact force: the measurement, as a rig samples its load cell.
    for (double now = steady_now(); now < next && keep_running(); now = steady_now()) {
      socket_.wait_readable(next);
      drain();
    }
    drain();
    if (over(keep_running, until_ended)) continue;
    send_measurement();
    next = next_rig_tick(next, period, steady_now(), missed_);
  }
}

}  // namespace hil
}  // namespace catenary_sim
