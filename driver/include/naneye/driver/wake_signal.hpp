#pragma once
// WakeSignal: lets a thread sleep until a lock-free condition becomes true, without putting a lock on
// the fast path. The signalling side publishes its change with a seq_cst store (or RMW), then calls
// notify(), which costs one load when nobody waits; the waiter's predicate loads seq_cst too. That
// is Dekker's pattern: in the single seq_cst order either the waiter sees the change or notify()
// sees the waiter (no fences: ThreadSanitizer does not model them). Waiters also re-check their
// predicate at least every 20 ms, so a wake-up lost to a bug could only delay, never hang.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>

namespace naneye::driver {

class WakeSignal {
 public:
  void notify() {
    if (waiters_.load(std::memory_order_seq_cst) == 0) return;
    { std::lock_guard lock(mutex_); }
    cv_.notify_all();
  }

  // Returns pred() as last evaluated: false means the deadline passed first.
  template <class Pred>
  bool wait_until(Pred pred, std::chrono::steady_clock::time_point deadline) {
    if (pred()) return true;
    std::unique_lock lock(mutex_);
    waiters_.fetch_add(1, std::memory_order_seq_cst);
    bool ok = pred();
    while (!ok) {
      const auto now = std::chrono::steady_clock::now();
      if (now >= deadline) break;
      cv_.wait_until(lock, std::min(deadline, now + std::chrono::milliseconds(20)));
      ok = pred();
    }
    waiters_.fetch_sub(1, std::memory_order_relaxed);
    return ok;
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::atomic<int> waiters_{0};
};

}  // namespace naneye::driver
