#pragma once
// Polls `done` every 2 ms until it holds or `timeout_ms` pass (a deadline, not a delay: tests that
// wait for a thread or an emulated device finish as soon as it is there).
#include <chrono>
#include <thread>

namespace naneye::test {

template <class F>
bool wait_until(F done, int timeout_ms = 10000) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

}  // namespace naneye::test
