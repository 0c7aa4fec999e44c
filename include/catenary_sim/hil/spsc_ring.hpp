// A lock-free single-producer / single-consumer ring of fixed capacity: the loop thread pushes,
// one monitoring thread pops, and neither ever waits for the other (realtime_tools is not in
// Debian 12). push() on a full ring drops the new item and counts it, so a stalled consumer costs
// the loop nothing. Capacity N (a power of two); T trivially copyable. No allocation after
// construction.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace catenary_sim {
namespace hil {

template <class T, std::size_t N>
class SpscRing {
  static_assert(N >= 2 && (N & (N - 1)) == 0, "SpscRing: capacity must be a power of two");
  static_assert(std::is_trivially_copyable<T>::value, "SpscRing: T must be trivially copyable");

 public:
  // Producer only. False (and counted) when the ring is full: the item is dropped.
  bool push(const T& item) {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) >= N) {
      dropped_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    slots_[head & (N - 1)] = item;
    head_.store(head + 1, std::memory_order_release);  // publishes the slot to the consumer
    return true;
  }
  // Consumer only. False when empty.
  bool pop(T& out) {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return false;
    out = slots_[tail & (N - 1)];
    tail_.store(tail + 1, std::memory_order_release);  // frees the slot for the producer
    return true;
  }
  std::size_t size() const { return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire); }
  static constexpr std::size_t capacity() { return N; }
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

 private:
  // (head and tail on cache lines of their own: the two threads do not share a line they write)
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
  alignas(64) std::atomic<std::uint64_t> dropped_{0};
  std::array<T, N> slots_{};
};

}  // namespace hil
}  // namespace catenary_sim
