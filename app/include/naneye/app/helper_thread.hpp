#pragma once
// A second thread for one part of the per-pair step ([recon] threads = 2: the dense map and the
// board beside the sparse points). The worker hands the part over with start() and takes it back with
// finish(), once per pair: two atomic counters and their futex waits (C++20 std::atomic::wait), no
// lock, no allocation, asleep while idle (libstdc++ spins only a few microseconds before the futex;
// a pool that spins while idle took the capture and HTTP threads' core: the reason make_processor
// sets OpenCV to one thread).
#include <atomic>
#include <cstdint>
#include <exception>
#include <functional>
#include <thread>

namespace naneye::app {

class HelperThread {
 public:
  // `part` runs once per start() on the helper thread; it is set once (per pair it reads what the
  // caller prepared before start()).
  explicit HelperThread(std::function<void()> part);
  ~HelperThread();  // waits for a running part, then ends the thread
  HelperThread(const HelperThread&) = delete;
  HelperThread& operator=(const HelperThread&) = delete;

  // The part begins on the helper. Everything it reads must stay as it is until finish().
  // One start() at a time: finish() comes before the next.
  void start();
  // Waits until the part started last has returned; rethrows what it threw (the helper goes on).
  void finish();

 private:
  void run();

  std::function<void()> part_;
  std::uint32_t requested_ = 0;  // the caller's count of start()s (only the caller touches it)
  std::atomic<std::uint32_t> started_{0}, finished_{0};
  std::atomic<bool> stop_{false};
  std::exception_ptr error_;  // written by the helper before finished_, read by the caller after
  std::thread thread_;
};

}  // namespace naneye::app
