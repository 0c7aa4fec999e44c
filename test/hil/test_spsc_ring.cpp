// hil::SpscRing: the lock-free single-producer / single-consumer handoff between the UDP loop and
// its monitoring thread. Order kept across threads, a full ring drops (and counts) the new item
// without waiting, and the consumer sees every item that was not dropped, each once.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

#include "catenary_sim/hil/spsc_ring.hpp"

using catenary_sim::hil::SpscRing;

TEST(SpscRing, FifoInOneThreadAndAFullRingDropsTheNewItem) {
  SpscRing<int, 8> r;
  int v = 0;
  EXPECT_FALSE(r.pop(v));
  for (int i = 0; i < 8; ++i) EXPECT_TRUE(r.push(i));
  EXPECT_EQ(r.size(), 8u);
  // Full: the producer is refused at once (no wait), the item dropped and counted.
  EXPECT_FALSE(r.push(100));
  EXPECT_FALSE(r.push(101));
  EXPECT_EQ(r.dropped(), 2u);
  for (int i = 0; i < 8; ++i) {
    ASSERT_TRUE(r.pop(v));
    EXPECT_EQ(v, i);  // the oldest first; the dropped ones never appear
  }
  EXPECT_FALSE(r.pop(v));
  // Wrapping around the storage many times keeps the order.
  for (int i = 0; i < 1000; ++i) {
    ASSERT_TRUE(r.push(i));
    ASSERT_TRUE(r.pop(v));
    ASSERT_EQ(v, i);
  }
  EXPECT_EQ(r.dropped(), 2u);
}

TEST(SpscRing, TwoThreadsSeeEveryItemInOrderOrCountedAsDropped) {
  // The producer never waits (as the loop): what the consumer does not take in time is dropped.
  // Whatever the timing, every item is either received, in increasing order, or counted dropped.
  struct Item {
    std::uint64_t seq;
    double payload[6];
  };
  SpscRing<Item, 64> r;
  constexpr std::uint64_t kItems = 2000000;
  std::atomic<bool> done{false};
  std::uint64_t received = 0, last = 0, disorder = 0, bad_payload = 0;
  std::thread consumer([&] {
    Item it;
    while (true) {
      const bool finished = done.load(std::memory_order_acquire);
      while (r.pop(it)) {
        if (received > 0 && it.seq <= last) ++disorder;
        if (it.payload[5] != static_cast<double>(it.seq)) ++bad_payload;  // (torn copy)
        last = it.seq;
        ++received;
      }
      if (finished) break;
    }
  });
  for (std::uint64_t i = 1; i <= kItems; ++i) {
    Item it{i, {0, 0, 0, 0, 0, static_cast<double>(i)}};
    r.push(it);
  }
  done.store(true, std::memory_order_release);
  consumer.join();
  EXPECT_EQ(disorder, 0u);
  EXPECT_EQ(bad_payload, 0u);
  EXPECT_EQ(received + r.dropped(), kItems);
  EXPECT_GT(received, 0u);
}
