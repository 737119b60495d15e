#pragma once
// PairRing: the hand-over from the one capture thread (producer) to the one consumer, lock-free.
// head_ (next to read) and tail_ (next to write) are 64-bit counters that never wrap in practice, so
// there is no ABA. Slots are atomics holding the raw StereoPair*; indices publish them with
// release/acquire.
//
// Policy drop_oldest (live capture): when the ring is full the producer takes the oldest pair away
// from the consumer by advancing head_ with a compare-exchange. The consumer claims a pair with the
// same compare-exchange (read the slot, then CAS head_ h -> h+1), so exactly one of them owns slot h:
// if the producer won, the consumer's CAS fails and it retries with the new head_, discarding the
// pointer it read (the producer may already have re-filled the slot, which is why slots are atomic).
// Policy block (lossless replay): the producer waits for room (or for stop) instead.
// Blocking waits use WakeSignal; the fast paths take no lock.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>

#include "naneye/driver/frame.hpp"
#include "naneye/driver/wake_signal.hpp"

namespace naneye::driver {

class PairRing {
 public:
  enum class Policy { drop_oldest, block };

  // `deleter` is the pool's (PairPool::deleter()): every pair pushed must come from that pool.
  PairRing(std::size_t capacity, Policy policy, PairReturn deleter);
  ~PairRing();
  PairRing(const PairRing&) = delete;
  PairRing& operator=(const PairRing&) = delete;

  // Producer. drop_oldest: never waits; a full ring loses its oldest pair (counted in dropped()).
  // block: waits for room; returns false (and releases the pair) if `stop` becomes true or the ring
  // was closed first.
  bool push(PairPtr pair, const std::atomic<bool>* stop = nullptr);
  // Producer: drops the oldest queued pair (returns its buffer to the pool); false if empty. Lets a
  // live producer recover a buffer when the pool runs dry.
  bool drop_oldest();

  // Consumer: the oldest pair, or nullptr if none.
  PairPtr try_pop();
  // Consumer: waits until a pair is there, the deadline passes, or the ring is closed and empty.
  PairPtr pop_until(std::chrono::steady_clock::time_point deadline);

  // No more pushes; wakes the consumer, which drains what is left then gets nullptr at once.
  void close();
  bool closed() const { return closed_.load(std::memory_order_seq_cst); }
  // Wakes a producer blocked in push() (after the caller set its stop flag).
  void wake_producer() { room_.notify(); }

  std::size_t capacity() const { return capacity_; }
  std::size_t size() const;
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

 private:
  std::atomic<StereoPair*>& slot(std::uint64_t i) { return slots_[i % capacity_]; }

  const std::size_t capacity_;
  const Policy policy_;
  const PairReturn deleter_;
  std::unique_ptr<std::atomic<StereoPair*>[]> slots_;
  alignas(64) std::atomic<std::uint64_t> head_{0};
  alignas(64) std::atomic<std::uint64_t> tail_{0};
  alignas(64) std::atomic<std::uint64_t> dropped_{0};
  std::atomic<bool> closed_{false};
  WakeSignal data_;  // consumer waits here
  WakeSignal room_;  // blocked producer waits here
};

}  // namespace naneye::driver
