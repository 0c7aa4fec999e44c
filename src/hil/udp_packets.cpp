#include "catenary_sim/hil/udp_packets.hpp"

#include "../core/util/format.hpp"  // the core's numbers in messages: one way for all

#include <cmath>
#include <algorithm>
#include <cstring>

namespace catenary_sim {
namespace hil {
namespace udp {

namespace {

// A jump of the sequence number this large (either way) is a sender that started again, not a
// loss: 2^20 packets are 100 s at 10 kHz.
constexpr std::int64_t kRestartJump = 1 << 20;

bool fail(Reject r, Reject& why, std::string& reason, std::string text) {
  why = r;
  reason = std::move(text);
  return false;
}

bool check_header(const void* data, std::size_t size, std::uint16_t kind, std::uint32_t expected_size,
                  const char* what, csim_udp_header& h, Reject& why, std::string& reason) {
  if (size < sizeof(csim_udp_header) || size != expected_size)
    return fail(Reject::kSize, why, reason,
                std::string(what) + " packet of " + std::to_string(size) + " bytes rejected: allowed exactly " +
                    std::to_string(expected_size) + " bytes (udp_packets.h)");
  std::memcpy(&h, data, sizeof h);
  if (h.magic != CSIM_UDP_MAGIC)
    return fail(Reject::kMagic, why, reason,
                std::string(what) + " header.magic = " + std::to_string(h.magic) + " rejected: allowed " +
                    std::to_string(CSIM_UDP_MAGIC) + " ('CSIM')");
  if (h.version != CSIM_UDP_VERSION)
    return fail(Reject::kVersion, why, reason,
                std::string(what) + " header.version = " + std::to_string(h.version) + " rejected: allowed " +
                    std::to_string(CSIM_UDP_VERSION));
  if (h.kind != kind)
    return fail(Reject::kKind, why, reason,
                std::string(what) + " header.kind = " + std::to_string(h.kind) + " rejected: allowed " +
                    std::to_string(kind));
  if (h.size != expected_size)
    return fail(Reject::kSize, why, reason,
                std::string(what) + " header.size = " + std::to_string(h.size) + " rejected: allowed " +
                    std::to_string(expected_size));
  return true;
}

bool finite_field(double v, const std::string& name, Reject& why, std::string& reason) {
  if (std::isfinite(v)) return true;
  return fail(Reject::kNonFinite, why, reason, name + " = " + fmt(v) + " rejected: allowed a finite value");
}

}  // namespace

const char* reject_name(Reject r) {
  switch (r) {
    case Reject::kSize: return "size";
    case Reject::kMagic: return "magic";
    case Reject::kVersion: return "version";
    case Reject::kKind: return "kind";
    case Reject::kCount: return "count";
    case Reject::kFlags: return "flags";
    case Reject::kNonFinite: return "non_finite";
    case Reject::kNumReasons: break;
  }
  return "unknown";
}

void fill_header(csim_udp_header& h, std::uint16_t kind, std::uint32_t size, std::uint32_t sequence,
                 std::int64_t send_time_ns) {
  h.magic = CSIM_UDP_MAGIC;
  h.version = CSIM_UDP_VERSION;
  h.kind = kind;
  h.size = size;
  h.sequence = sequence;
  h.send_time_ns = send_time_ns;
}

bool decode_measurement(const void* data, std::size_t size, std::uint32_t pantographs, csim_udp_measurement& out,
                        Reject& why, std::string& reason) {
  csim_udp_header h;
  if (!check_header(data, size, CSIM_UDP_KIND_MEASUREMENT, CSIM_UDP_MEASUREMENT_SIZE, "measurement", h, why, reason))
    return false;
  csim_udp_measurement m;
  std::memcpy(&m, data, sizeof m);
  if (m.pantographs != pantographs && m.pantographs != 0)
    return fail(Reject::kCount, why, reason,
                "measurement.pantographs = " + std::to_string(m.pantographs) + " rejected: allowed " +
                    std::to_string(pantographs) + " (the scene's external pantographs: one total force each, in scene "
                    "order) or 0 (a hello)");
  if (m.flags & ~CSIM_UDP_HAS_HEAD_ACCELERATION)
    return fail(Reject::kFlags, why, reason,
                "measurement.flags = " + std::to_string(m.flags) + " rejected: allowed 0 or " +
                    std::to_string(CSIM_UDP_HAS_HEAD_ACCELERATION) + " (head acceleration present)");
  for (std::uint32_t i = 0; i < m.pantographs; ++i) {
    if (!finite_field(m.force[i], "measurement.force[" + std::to_string(i) + "]", why, reason)) return false;
    if ((m.flags & CSIM_UDP_HAS_HEAD_ACCELERATION) &&
        !finite_field(m.head_acceleration[i], "measurement.head_acceleration[" + std::to_string(i) + "]", why, reason))
      return false;
  }
  out = m;
  return true;
}

bool decode_contact_point(const void* data, std::size_t size, csim_udp_contact_point& out, Reject& why,
                          std::string& reason) {
  csim_udp_header h;
  if (!check_header(data, size, CSIM_UDP_KIND_CONTACT_POINT, CSIM_UDP_CONTACT_POINT_SIZE, "contact point", h, why,
                    reason))
    return false;
  std::memcpy(&out, data, sizeof out);
  if (out.pantographs == 0 || out.pantographs > CSIM_UDP_MAX_PANTOGRAPHS)
    return fail(Reject::kCount, why, reason,
                "contact_point.pantographs = " + std::to_string(out.pantographs) + " rejected: allowed 1 to " +
                    std::to_string(CSIM_UDP_MAX_PANTOGRAPHS));
  if ((out.state_flags & CSIM_UDP_MODE_MASK) > CSIM_UDP_MODE_PAUSED)
    return fail(Reject::kFlags, why, reason,
                "contact_point.state_flags mode = " + std::to_string(out.state_flags & CSIM_UDP_MODE_MASK) +
                    " rejected: allowed 0 to 4");
  for (const auto& [v, name] : {std::pair<double, const char*>{out.simulation_time, "simulation_time"},
                                {out.dt, "dt"}, {out.speed, "speed"}})
    if (!finite_field(v, std::string("contact_point.") + name, why, reason)) return false;
  for (std::uint32_t i = 0; i < out.pantographs; ++i) {
    const csim_udp_pantograph_point& p = out.pantograph[i];
    const std::string at = "contact_point.pantograph[" + std::to_string(i) + "].";
    if (p.wire_points > CSIM_UDP_MAX_WIRE_POINTS)
      return fail(Reject::kCount, why, reason,
                  at + "wire_points = " + std::to_string(p.wire_points) + " rejected: allowed 0 to " +
                      std::to_string(CSIM_UDP_MAX_WIRE_POINTS));
    for (double v : {p.position, p.height, p.velocity, p.acceleration, p.path_velocity, p.applied_force,
                     p.measurement_age})
      if (!finite_field(v, at + "(a motion field)", why, reason)) return false;
    for (std::uint32_t k = 0; k < p.wire_points; ++k)
      for (double v : {p.wire_height[k], p.wire_velocity[k], p.wire_path_velocity[k], p.wire_force[k]})
        if (!finite_field(v, at + "wire[" + std::to_string(k) + "]", why, reason)) return false;
  }
  return true;
}

std::uint16_t kind_of(const void* data, std::size_t size) {
  if (size < sizeof(csim_udp_header)) return 0;
  csim_udp_header h;
  std::memcpy(&h, data, sizeof h);
  return h.kind;
}

const char* end_reason_name(std::uint32_t reason) {
  switch (reason) {
    case CSIM_UDP_END_FINISHED: return "the pass ended";
    case CSIM_UDP_END_DIVERGED: return "the simulation diverged";
    case CSIM_UDP_END_SHUTDOWN: return "the simulator stopped";
    case CSIM_UDP_END_DEWIRED: return "the pass stopped at a dewirement";
    default: return "unknown";
  }
}

bool decode_end(const void* data, std::size_t size, csim_udp_end& out, Reject& why, std::string& reason) {
  csim_udp_header h;
  if (!check_header(data, size, CSIM_UDP_KIND_END, CSIM_UDP_END_SIZE, "end", h, why, reason)) return false;
  std::memcpy(&out, data, sizeof out);
  if (out.reason < CSIM_UDP_END_FINISHED || out.reason > CSIM_UDP_END_DEWIRED)
    return fail(Reject::kFlags, why, reason,
                "end.reason = " + std::to_string(out.reason) + " rejected: allowed 1 to 4 (CSIM_UDP_END_*)");
  return finite_field(out.simulation_time, "end.simulation_time", why, reason);
}

std::string check_fits(const Model& m) {
  const std::vector<int> ext = external_pantographs(m);
  if (ext.size() > CSIM_UDP_MAX_PANTOGRAPHS)
    return "the scene has " + std::to_string(ext.size()) + " external pantographs: a UDP packet carries at most " +
           std::to_string(CSIM_UDP_MAX_PANTOGRAPHS);
  for (int p : ext) {
    const std::size_t n = m.pantographs[p].collectors.size() * m.contact_wires.size();
    if (n > CSIM_UDP_MAX_WIRE_POINTS)
      return "pantograph '" + m.pantographs[p].name + "' has " + std::to_string(n) +
             " collector x contact-wire points: a UDP packet carries at most " + std::to_string(CSIM_UDP_MAX_WIRE_POINTS);
  }
  return {};
}

bool encode_contact_point(const PointFrame& f, std::uint32_t sequence, std::int64_t send_time_ns,
                          std::uint32_t measurement_sequence, std::uint32_t flags, csim_udp_contact_point& out,
                          std::string* reason) {
  if (f.pantographs.size() > CSIM_UDP_MAX_PANTOGRAPHS) {
    if (reason) *reason = "too many pantographs for a UDP packet";
    return false;
  }
  std::memset(&out, 0, sizeof out);
  fill_header(out.header, CSIM_UDP_KIND_CONTACT_POINT, CSIM_UDP_CONTACT_POINT_SIZE, sequence, send_time_ns);
  out.step = f.step;
  out.measurement_step = f.measurement_step;
  out.measurement_sequence = measurement_sequence;
  out.state_flags = (static_cast<std::uint32_t>(f.mode) & CSIM_UDP_MODE_MASK) | (flags & ~CSIM_UDP_MODE_MASK);
  out.pass_count = f.pass_count;
  out.pantographs = static_cast<std::uint32_t>(f.pantographs.size());
  out.steps_per_period = f.steps_per_period;
  out.simulation_time = f.simulation_time;
  out.dt = f.dt;
  out.speed = f.speed;
  for (std::size_t i = 0; i < f.pantographs.size(); ++i) {
    const PantographPoint& c = f.pantographs[i];
    csim_udp_pantograph_point& p = out.pantograph[i];
    if (c.wires.size() > CSIM_UDP_MAX_WIRE_POINTS) {
      if (reason) *reason = "too many wire points for a UDP packet";
      return false;
    }
    p.position = c.position;
    p.height = c.height;
    p.velocity = c.velocity;
    p.acceleration = c.acceleration;
    p.path_velocity = c.path_velocity;
    p.applied_force = c.applied_force;
    p.measurement_age = c.measurement_age;
    p.wire_points = static_cast<std::uint32_t>(c.wires.size());
    for (std::size_t k = 0; k < c.wires.size(); ++k) {
      const ContactPointMotion& w = c.wires[k];
      p.on_wire[k] = w.on_wire ? 1 : 0;
      p.wire_height[k] = w.on_wire ? w.height : 0.0;
      p.wire_velocity[k] = w.on_wire ? w.velocity : 0.0;
      p.wire_path_velocity[k] = w.on_wire ? w.path_velocity : 0.0;
      p.wire_force[k] = w.force;
    }
  }
  return true;
}

SequenceTracker::Verdict SequenceTracker::observe(std::uint32_t seq) {
  ++received_;
  if (!any_) {
    any_ = true;
    rejected_since_ = 0;
    newest_ = seq;
    seen_ = 1;
    return Verdict::kFirst;
  }
  // Signed distance modulo 2^32: the numbering may wrap.
  const std::int64_t d = static_cast<std::int32_t>(seq - newest_);
  if (d > kRestartJump || d < -kRestartJump) {
    ++restarts_;
    rejected_since_ = 0;
    newest_ = seq;
    seen_ = 1;
    return Verdict::kRestart;
  }
  if (d > 0) {
    run_ = 0;
    const std::uint64_t gap = static_cast<std::uint64_t>(d - 1);
    lost_ += gap - std::min(gap, rejected_since_);
    rejected_since_ = 0;
    seen_ = d >= 64 ? 1 : ((seen_ << d) | 1);
    newest_ = seq;
    return d == 1 ? Verdict::kInOrder : Verdict::kGap;
  }
  // Older than the newest: the start of the sender's numbering again, when kResyncRun in a row.
  run_ = run_ > 0 && seq == run_next_ ? run_ + 1 : 1;
  run_next_ = seq + 1;
  if (run_ >= kResyncRun) {
    ++restarts_;
    newest_ = seq;
    seen_ = 1;
    run_ = 0;
    return Verdict::kRestart;
  }
  if (d == 0) {
    ++duplicates_;
    return Verdict::kDuplicate;
  }
  const std::int64_t age = -d;
  if (age < 64) {
    const std::uint64_t bit = std::uint64_t{1} << age;
    if (seen_ & bit) {
      ++duplicates_;
      return Verdict::kDuplicate;
    }
    seen_ |= bit;
    if (lost_ > 0) --lost_;  // (it was counted lost when the gap opened)
  }
  ++reordered_;
  return Verdict::kReordered;
}

void SequenceTracker::restart(bool counted) {
  if (!any_) return;
  any_ = false;
  run_ = 0;
  if (counted) ++restarts_;
}

}  // namespace udp
}  // namespace hil
}  // namespace catenary_sim
