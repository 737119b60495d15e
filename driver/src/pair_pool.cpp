#include "naneye/driver/pair_pool.hpp"

#include "log.hpp"

namespace naneye::driver {

PairPool::PairPool(std::size_t capacity)
    : capacity_(capacity), storage_(std::make_unique<StereoPair[]>(capacity)) {
  free_.reserve(capacity);
  for (std::size_t i = capacity; i > 0; --i) free_.push_back(&storage_[i - 1]);
  free_count_.store(capacity);
}

PairPool::~PairPool() {
  if (available() != capacity_)
    log()->error("pair pool destroyed with {} of {} buffers still handed out", capacity_ - available(),
                 capacity_);
}

PairPtr PairPool::try_acquire() {
  std::lock_guard lock(mutex_);
  if (free_.empty()) return PairPtr(nullptr, PairReturn{this, &PairPool::give_back});
  StereoPair* p = free_.back();
  free_.pop_back();
  free_count_.store(free_.size(), std::memory_order_seq_cst);
  return PairPtr(p, PairReturn{this, &PairPool::give_back});
}

PairPtr PairPool::acquire_until(std::chrono::steady_clock::time_point deadline,
                                const std::atomic<bool>* stop) {
  PairPtr p = try_acquire();
  while (!p) {
    const bool woke = released_.wait_until(
        [&] {
          return free_count_.load(std::memory_order_seq_cst) > 0 ||
                 (stop && stop->load(std::memory_order_seq_cst));
        },
        deadline);
    if (!woke || (stop && stop->load(std::memory_order_acquire))) return p;
    p = try_acquire();
  }
  return p;
}

std::size_t PairPool::available() const {
  std::lock_guard lock(mutex_);
  return free_.size();
}

void PairPool::give_back(void* pool, StereoPair* pair) {
  static_cast<PairPool*>(pool)->release(pair);
}

void PairPool::release(StereoPair* pair) {
  {
    std::lock_guard lock(mutex_);
    free_.push_back(pair);  // never reallocates: at most capacity_ buffers exist
    free_count_.store(free_.size(), std::memory_order_seq_cst);
  }
  released_.notify();
}

}  // namespace naneye::driver
