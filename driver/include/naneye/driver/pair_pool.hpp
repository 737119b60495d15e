#pragma once
// PairPool: a fixed set of StereoPair buffers allocated once at construction. acquire() hands one
// out as a PairPtr whose deleter gives it back; nothing is allocated afterwards, whatever the frame
// rate. Any thread may release a pair; acquire is meant for the one capture thread.
// The pool must outlive every PairPtr it handed out (sources own their pool: release pairs before
// destroying the source).
#include <atomic>
#include <chrono>
#include <cstddef>
#include <memory>
#include <mutex>
#include <vector>

#include "naneye/driver/frame.hpp"
#include "naneye/driver/wake_signal.hpp"

namespace naneye::driver {

class PairPool {
 public:
  explicit PairPool(std::size_t capacity);
  ~PairPool();
  PairPool(const PairPool&) = delete;
  PairPool& operator=(const PairPool&) = delete;

  // A free buffer, or nullptr when all are out.
  PairPtr try_acquire();
  // Waits for a free buffer until `deadline` or until `stop` becomes true.
  PairPtr acquire_until(std::chrono::steady_clock::time_point deadline,
                        const std::atomic<bool>* stop = nullptr);

  // The deleter every PairPtr of this pool carries (a PairRing needs it to rebuild handles).
  PairReturn deleter() { return PairReturn{this, &PairPool::give_back}; }
  std::size_t capacity() const { return capacity_; }
  std::size_t available() const;
  // True if `p` is one of this pool's buffers (tests, sanity checks).
  bool owns(const StereoPair* p) const { return p >= storage_.get() && p < storage_.get() + capacity_; }

 private:
  static void give_back(void* pool, StereoPair* pair);
  void release(StereoPair* pair);

  std::size_t capacity_;
  std::unique_ptr<StereoPair[]> storage_;
  mutable std::mutex mutex_;
  std::vector<StereoPair*> free_;  // reserved to capacity_: push/pop never allocate
  std::atomic<std::size_t> free_count_{0};
  WakeSignal released_;
};

}  // namespace naneye::driver
