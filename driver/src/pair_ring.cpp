#include "naneye/driver/pair_ring.hpp"

#include <stdexcept>

namespace naneye::driver {

PairRing::PairRing(std::size_t capacity, Policy policy, PairReturn deleter)
    : capacity_(capacity),
      policy_(policy),
      deleter_(deleter),
      slots_(new std::atomic<StereoPair*>[capacity]) {
  if (capacity == 0) throw std::invalid_argument("PairRing capacity must be at least 1");
  for (std::size_t i = 0; i < capacity; ++i) slots_[i].store(nullptr, std::memory_order_relaxed);
}

PairRing::~PairRing() {
  while (try_pop()) {
  }
}

std::size_t PairRing::size() const {
  const std::uint64_t t = tail_.load(std::memory_order_acquire);
  const std::uint64_t h = head_.load(std::memory_order_acquire);
  return static_cast<std::size_t>(t - h);
}

bool PairRing::drop_oldest() {
  std::uint64_t h = head_.load(std::memory_order_acquire);
  const std::uint64_t t = tail_.load(std::memory_order_relaxed);  // only this (producer) thread writes tail_
  while (h != t) {
    StereoPair* p = slot(h).load(std::memory_order_acquire);
    if (head_.compare_exchange_weak(h, h + 1, std::memory_order_seq_cst, std::memory_order_acquire)) {
      // Slot h is ours now; it cannot be refilled before we write tail_ again.
      dropped_.fetch_add(1, std::memory_order_relaxed);
      PairPtr gone(p, deleter_);
      room_.notify();
      return true;
    }
  }
  return false;
}

bool PairRing::push(PairPtr pair, const std::atomic<bool>* stop) {
  if (closed()) return false;
  const std::uint64_t t = tail_.load(std::memory_order_relaxed);
  if (t - head_.load(std::memory_order_acquire) >= capacity_) {
    if (policy_ == Policy::drop_oldest) {
      drop_oldest();  // the consumer may also have freed a slot meanwhile: either way there is room
    } else {
      const bool room = room_.wait_until(
          [&] {
            return t - head_.load(std::memory_order_seq_cst) < capacity_ || closed() ||
                   (stop && stop->load(std::memory_order_seq_cst));
          },
          std::chrono::steady_clock::time_point::max());
      if (!room || closed() || t - head_.load(std::memory_order_acquire) >= capacity_) return false;
    }
  }
  slot(t).store(pair.release(), std::memory_order_release);
  tail_.store(t + 1, std::memory_order_seq_cst);  // seq_cst: see WakeSignal
  data_.notify();
  return true;
}

PairPtr PairRing::try_pop() {
  std::uint64_t h = head_.load(std::memory_order_acquire);
  while (h != tail_.load(std::memory_order_acquire)) {
    StereoPair* p = slot(h).load(std::memory_order_acquire);
    if (head_.compare_exchange_weak(h, h + 1, std::memory_order_seq_cst, std::memory_order_acquire)) {
      if (policy_ == Policy::block) room_.notify();
      return PairPtr(p, deleter_);
    }
    // Lost to the producer dropping the oldest (or a spurious failure): h now holds the new head.
  }
  return PairPtr(nullptr, deleter_);
}

PairPtr PairRing::pop_until(std::chrono::steady_clock::time_point deadline) {
  PairPtr p = try_pop();
  while (!p) {
    const bool ready = data_.wait_until(
        [&] {
          return tail_.load(std::memory_order_seq_cst) != head_.load(std::memory_order_seq_cst) || closed();
        },
        deadline);
    p = try_pop();
    if (!ready || (!p && closed())) break;
  }
  return p;
}

void PairRing::close() {
  closed_.store(true, std::memory_order_seq_cst);
  data_.notify();
  room_.notify();
}

}  // namespace naneye::driver
