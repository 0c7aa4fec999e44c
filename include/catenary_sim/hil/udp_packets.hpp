// The UDP packets of udp_packets.h in C++: encoding, decoding with validation (a bad packet is
// rejected with the reason, naming the field, the value and what is allowed) and the detection of
// lost, reordered and duplicated packets from their sequence numbers. No allocation on the good
// path; no ROS.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "catenary_sim/hil/loop.hpp"
#include "catenary_sim/hil/udp_packets.h"

namespace catenary_sim {
namespace hil {
namespace udp {

static_assert(sizeof(csim_udp_header) == 24, "udp_packets.h: header layout");
static_assert(sizeof(csim_udp_measurement) == CSIM_UDP_MEASUREMENT_SIZE, "udp_packets.h: measurement layout");
static_assert(sizeof(csim_udp_pantograph_point) == 324, "udp_packets.h: pantograph point layout");
static_assert(sizeof(csim_udp_contact_point) == CSIM_UDP_CONTACT_POINT_SIZE, "udp_packets.h: contact point layout");
static_assert(sizeof(csim_udp_end) == CSIM_UDP_END_SIZE, "udp_packets.h: end layout");
// The packets are little-endian and copied as they are: this build serves little-endian hosts.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the UDP packets are little-endian: port encode/decode");

// Why a packet was rejected (counted per reason).
enum class Reject : int { kSize, kMagic, kVersion, kKind, kCount, kFlags, kNonFinite, kNumReasons };
const char* reject_name(Reject r);

// Fills the header (magic, version, kind, size) and the sequence and send time.
void fill_header(csim_udp_header& h, std::uint16_t kind, std::uint32_t size, std::uint32_t sequence,
                 std::int64_t send_time_ns);

// Checks a received datagram as a measurement for a scene with `pantographs` external ones. On
// success copies it into `out` and returns true; else sets `why` and `reason` (the field, the
// value and what is allowed) and returns false. Range checks of the forces are the loop's
// (HilLoop::accept, shared with the ROS transport).
bool decode_measurement(const void* data, std::size_t size, std::uint32_t pantographs, csim_udp_measurement& out,
                        Reject& why, std::string& reason);
// The same for a contact point (a rig's side): counts at most the maxima, values finite.
bool decode_contact_point(const void* data, std::size_t size, csim_udp_contact_point& out, Reject& why,
                          std::string& reason);

// The same for an end packet (a rig's side): the reason one of CSIM_UDP_END_*.
bool decode_end(const void* data, std::size_t size, csim_udp_end& out, Reject& why, std::string& reason);
// The kind of a datagram that carries a header (0: too short for one).
std::uint16_t kind_of(const void* data, std::size_t size);
// "the pass ended", "the simulation diverged", "the simulator stopped", "the pass stopped at a
// dewirement" for CSIM_UDP_END_*.
const char* end_reason_name(std::uint32_t reason);

// The contact point packet of a loop frame. Fails (false, `reason`) when the frame does not fit
// (more than CSIM_UDP_MAX_PANTOGRAPHS pantographs or CSIM_UDP_MAX_WIRE_POINTS wire points).
bool encode_contact_point(const PointFrame& f, std::uint32_t sequence, std::int64_t send_time_ns,
                          std::uint32_t measurement_sequence, std::uint32_t flags, csim_udp_contact_point& out,
                          std::string* reason = nullptr);
// Empty when every frame of this model fits a packet, else why not.
std::string check_fits(const Model& m);

// Lost, reordered and duplicated packets of one sender, from their sequence numbers. A packet is
// `usable` when it is newer than every one before (the loop uses only the newest measurement: an
// older one that arrives late is counted and dropped). A sender that numbers again from lower
// down (it restarted, or one packet jumped far ahead) would otherwise be dropped until it passes
// its old newest number: kResyncRun consecutive numbers, each older than the newest, are taken as
// the sender's numbering from then on (a restart). Reordering in a network delays single packets
// or short bursts behind newer ones; 8 consecutive late ones in a row are not that.
class SequenceTracker {
 public:
  static constexpr int kResyncRun = 8;
  enum class Verdict { kFirst, kInOrder, kGap, kReordered, kDuplicate, kRestart };
  Verdict observe(std::uint32_t sequence);
  // The sender starts numbering again (a hello after its restart): the next number is taken as
  // the first; the counts are kept, and the restart counted unless `counted` is false (a new
  // pass's rig).
  void restart(bool counted = true);
  // True when `sequence` is not newer than the newest taken (a sender numbering again).
  bool behind(std::uint32_t sequence) const {
    return any_ && static_cast<std::int32_t>(sequence - newest_) <= 0;
  }
  static bool usable(Verdict v) { return v != Verdict::kReordered && v != Verdict::kDuplicate; }
  // A packet of the sender that was rejected (it did not decode, or its values were refused): its
  // number is not taken (it may be garbage), but the next gap is not counted lost for it (it came,
  // and is counted as rejected).
  void rejected() { ++rejected_since_; }
  std::uint64_t received() const { return received_; }
  std::uint64_t lost() const { return lost_; }          // skipped and not arrived since (within 64)
  std::uint64_t reordered() const { return reordered_; }  // arrived after a newer one
  std::uint64_t duplicates() const { return duplicates_; }
  std::uint64_t restarts() const { return restarts_; }  // the sender started numbering again
  std::uint32_t newest() const { return newest_; }
  void clear() { *this = SequenceTracker(); }

 private:
  bool any_ = false;
  std::uint32_t newest_ = 0;
  std::uint64_t seen_ = 0;  // bit i: newest_ - i arrived
  int run_ = 0;               // consecutive numbers older than newest_, ending at run_next_ - 1
  std::uint32_t run_next_ = 0;
  std::uint64_t rejected_since_ = 0;  // rejected packets since the newest taken
  std::uint64_t received_ = 0, lost_ = 0, reordered_ = 0, duplicates_ = 0, restarts_ = 0;
};

}  // namespace udp
}  // namespace hil
}  // namespace catenary_sim
