// The UDP packets (udp_packets.h / udp_packets.hpp): round trip, the stated byte order and
// sizes, bad packets rejected with their reason, and lost / reordered / duplicated packets counted.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "catenary_sim/hil/udp_packets.hpp"

using namespace catenary_sim;
using namespace catenary_sim::hil;
using namespace catenary_sim::hil::udp;

namespace {

csim_udp_measurement measurement(std::uint32_t seq, double f0, double f1) {
  csim_udp_measurement m;
  std::memset(&m, 0, sizeof m);
  fill_header(m.header, CSIM_UDP_KIND_MEASUREMENT, CSIM_UDP_MEASUREMENT_SIZE, seq, 123456789);
  m.answers_step = 42;
  m.measured_time_ns = 987654321;
  m.pantographs = 2;
  m.flags = CSIM_UDP_HAS_HEAD_ACCELERATION;
  m.force[0] = f0;
  m.force[1] = f1;
  m.head_acceleration[0] = -3.5;
  m.head_acceleration[1] = 2.25;
  return m;
}

std::vector<std::uint8_t> bytes(const void* p, std::size_t n) {
  const auto* b = static_cast<const std::uint8_t*>(p);
  return std::vector<std::uint8_t>(b, b + n);
}

}  // namespace

TEST(UdpPackets, MeasurementRoundTripKeepsEveryField) {
  const csim_udp_measurement m = measurement(7, 120.5, 0.0);
  const std::vector<std::uint8_t> wire = bytes(&m, sizeof m);
  csim_udp_measurement d;
  Reject why;
  std::string reason;
  ASSERT_TRUE(decode_measurement(wire.data(), wire.size(), 2, d, why, reason)) << reason;
  EXPECT_EQ(std::memcmp(&m, &d, sizeof m), 0);
  EXPECT_EQ(d.header.sequence, 7u);
  EXPECT_EQ(d.answers_step, 42u);
  EXPECT_EQ(d.force[0], 120.5);
  EXPECT_EQ(d.head_acceleration[1], 2.25);
}

TEST(UdpPackets, ByteOrderIsLittleEndianAsStated) {
  // The layout of udp_packets.h byte by byte: a rig on another compiler must find each field at
  // its offset, least significant byte first.
  const csim_udp_measurement m = measurement(0x01020304u, 1.0, 2.0);
  const std::vector<std::uint8_t> b = bytes(&m, sizeof m);
  ASSERT_EQ(b.size(), 112u);
  EXPECT_EQ(b[0], 'C');  // magic "CSIM"
  EXPECT_EQ(b[1], 'S');
  EXPECT_EQ(b[2], 'I');
  EXPECT_EQ(b[3], 'M');
  EXPECT_EQ(b[4], 1);  // version 1, LE
  EXPECT_EQ(b[5], 0);
  EXPECT_EQ(b[6], 1);  // kind measurement
  EXPECT_EQ(b[8], 112);  // size 112
  EXPECT_EQ(b[12], 0x04);  // sequence 0x01020304 at offset 12, least significant first
  EXPECT_EQ(b[13], 0x03);
  EXPECT_EQ(b[14], 0x02);
  EXPECT_EQ(b[15], 0x01);
  // force[0] = 1.0 at offset 48: IEEE 754 0x3FF0000000000000, LE
  const std::uint8_t one[8] = {0, 0, 0, 0, 0, 0, 0xF0, 0x3F};
  EXPECT_EQ(std::memcmp(b.data() + 48, one, 8), 0);
  EXPECT_EQ(offsetof(csim_udp_contact_point, pantograph), 88u);
  EXPECT_EQ(sizeof(csim_udp_contact_point), 1384u);  // one datagram within an Ethernet MTU (1472)
}

TEST(UdpPackets, BadPacketsAreRejectedWithTheirReason) {
  csim_udp_measurement d;
  Reject why;
  std::string reason;
  const csim_udp_measurement good = measurement(1, 100.0, 90.0);
  auto check = [&](csim_udp_measurement m, std::size_t size, Reject expected, const char* field) {
    std::vector<std::uint8_t> b = bytes(&m, sizeof m);
    b.resize(size, 0);
    std::memset(&d, 0x5A, sizeof d);
    const csim_udp_measurement before = d;
    EXPECT_FALSE(decode_measurement(b.data(), b.size(), 2, d, why, reason)) << field;
    EXPECT_EQ(static_cast<int>(why), static_cast<int>(expected)) << field << ": " << reason;
    EXPECT_NE(reason.find(field), std::string::npos) << reason;
    EXPECT_NE(reason.find("allowed"), std::string::npos) << reason;
    EXPECT_EQ(std::memcmp(&d, &before, sizeof d), 0) << "a rejected packet changes nothing";
  };
  check(good, 111, Reject::kSize, "111 bytes");
  check(good, 0, Reject::kSize, "0 bytes");
  check(good, 2000, Reject::kSize, "2000 bytes");
  csim_udp_measurement m = good;
  m.header.magic = 0xDEADBEEF;
  check(m, sizeof m, Reject::kMagic, "magic");
  m = good;
  m.header.version = 2;
  check(m, sizeof m, Reject::kVersion, "version = 2");
  m = good;
  m.header.kind = CSIM_UDP_KIND_CONTACT_POINT;
  check(m, sizeof m, Reject::kKind, "kind = 2");
  m = good;
  m.header.size = 100;
  check(m, sizeof m, Reject::kSize, "header.size = 100");
  m = good;
  m.pantographs = 1;
  check(m, sizeof m, Reject::kCount, "pantographs = 1");
  m = good;
  m.flags = 6;
  check(m, sizeof m, Reject::kFlags, "flags = 6");
  m = good;
  m.force[1] = std::numeric_limits<double>::quiet_NaN();
  check(m, sizeof m, Reject::kNonFinite, "force[1] = nan");
  m = good;
  m.force[0] = -std::numeric_limits<double>::infinity();
  check(m, sizeof m, Reject::kNonFinite, "force[0] = -inf");
  m = good;
  m.head_acceleration[0] = std::numeric_limits<double>::infinity();
  check(m, sizeof m, Reject::kNonFinite, "head_acceleration[0] = inf");
  m.flags = 0;  // (kept below: without the flag the junk is not read)
  // A hello (no pantographs) is valid: it tells the simulator where the rig is.
  csim_udp_measurement hello = good;
  hello.pantographs = 0;
  EXPECT_TRUE(decode_measurement(&hello, sizeof hello, 2, d, why, reason)) << reason;
  // Without the flag the head accelerations are not read (a rig without the sensor sends junk).
  EXPECT_TRUE(decode_measurement(&m, sizeof m, 2, d, why, reason)) << reason;
}

TEST(UdpPackets, ContactPointRoundTripFromALoopFrame) {
  PointFrame f;
  f.simulation_time = 1.25;
  f.dt = 5e-4;
  f.speed = 83.3;
  f.step = 2500;
  f.measurement_step = 2498;
  f.pass_count = 3;
  f.steps_per_period = 2;
  f.mode = Mode::kHold;
  f.pantographs.resize(1);
  PantographPoint& p = f.pantographs[0];
  p.position = 12.5;
  p.height = 5.301;
  p.velocity = -0.1;
  p.acceleration = 2.0;
  p.path_velocity = 0.05;
  p.applied_force = 140.0;
  p.measurement_age = 0.001;
  p.wires.resize(2);
  p.wires[0].on_wire = true;
  p.wires[0].height = 5.301;
  p.wires[0].force = 140.0;
  p.wires[1].on_wire = false;
  p.wires[1].height = 99.0;  // not under the wire: sent as 0
  csim_udp_contact_point out;
  ASSERT_TRUE(encode_contact_point(f, 9, 1000, 8, CSIM_UDP_FLAG_HELD, out));
  csim_udp_contact_point back;
  Reject why;
  std::string reason;
  ASSERT_TRUE(decode_contact_point(&out, sizeof out, back, why, reason)) << reason;
  EXPECT_EQ(back.step, 2500u);
  EXPECT_EQ(back.measurement_sequence, 8u);
  EXPECT_EQ(back.state_flags & CSIM_UDP_MODE_MASK, CSIM_UDP_MODE_SAFE_HOLD);
  EXPECT_TRUE(back.state_flags & CSIM_UDP_FLAG_HELD);
  EXPECT_EQ(back.pantograph[0].height, 5.301);
  EXPECT_EQ(back.pantograph[0].wire_points, 2u);
  EXPECT_EQ(back.pantograph[0].on_wire[1], 0);
  EXPECT_EQ(back.pantograph[0].wire_height[1], 0.0);
  out.pantograph[0].wire_force[1] = std::nan("");
  EXPECT_FALSE(decode_contact_point(&out, sizeof out, back, why, reason));
  EXPECT_NE(reason.find("pantograph[0].wire[1]"), std::string::npos) << reason;
}

TEST(SequenceTracker, CountsLossReorderAndDuplicates) {
  SequenceTracker t;
  using V = SequenceTracker::Verdict;
  EXPECT_EQ(t.observe(10), V::kFirst);
  EXPECT_EQ(t.observe(11), V::kInOrder);
  EXPECT_EQ(t.observe(14), V::kGap);  // 12 and 13 missing
  EXPECT_EQ(t.lost(), 2u);
  EXPECT_EQ(t.observe(12), V::kReordered);  // late: no longer lost, but not usable
  EXPECT_FALSE(SequenceTracker::usable(V::kReordered));
  EXPECT_EQ(t.lost(), 1u);
  EXPECT_EQ(t.reordered(), 1u);
  EXPECT_EQ(t.observe(12), V::kDuplicate);
  EXPECT_EQ(t.observe(14), V::kDuplicate);
  EXPECT_EQ(t.duplicates(), 2u);
  EXPECT_EQ(t.observe(15), V::kInOrder);
  EXPECT_EQ(t.received(), 7u);
  EXPECT_EQ(t.newest(), 15u);
}

TEST(SequenceTracker, WrapsAroundAndSeesARestart) {
  SequenceTracker t;
  using V = SequenceTracker::Verdict;
  t.observe(0xFFFFFFFEu);
  EXPECT_EQ(t.observe(0xFFFFFFFFu), V::kInOrder);
  EXPECT_EQ(t.observe(0u), V::kInOrder);  // wraps: no loss
  EXPECT_EQ(t.observe(2u), V::kGap);
  EXPECT_EQ(t.lost(), 1u);
  EXPECT_EQ(t.observe(0xFFFFFFFFu), V::kDuplicate);
  // A rig that restarts numbers from 1 after millions of packets: a restart, not 2^31 lost.
  for (std::uint32_t s = 3; s < 3000000; s += 1000) t.observe(s);
  const std::uint64_t lost = t.lost();
  EXPECT_EQ(t.observe(1u), V::kRestart);
  EXPECT_EQ(t.lost(), lost);
  EXPECT_EQ(t.restarts(), 1u);
  EXPECT_EQ(t.observe(2u), V::kInOrder);
}
