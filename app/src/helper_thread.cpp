#include "naneye/app/helper_thread.hpp"

#include <utility>

namespace naneye::app {

HelperThread::HelperThread(std::function<void()> part) : part_(std::move(part)) {
  thread_ = std::thread([this] { run(); });
}

HelperThread::~HelperThread() {
  if (requested_ != finished_.load(std::memory_order_acquire)) {
    try {
      finish();
    } catch (...) {  // a destructor cannot report it; the caller that skipped finish() lost it
    }
  }
  stop_.store(true, std::memory_order_relaxed);
  // A count the helper has not seen wakes it; stop_ (ordered before by the release) ends it.
  started_.fetch_add(1, std::memory_order_release);
  started_.notify_one();
  thread_.join();
}

void HelperThread::start() {
  ++requested_;
  started_.store(requested_, std::memory_order_release);  // publishes what the caller prepared
  started_.notify_one();
}

void HelperThread::finish() {
  for (std::uint32_t f = finished_.load(std::memory_order_acquire); f != requested_;
       f = finished_.load(std::memory_order_acquire))
    finished_.wait(f, std::memory_order_acquire);
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
}

void HelperThread::run() {
  std::uint32_t seen = 0;
  for (;;) {
    started_.wait(seen, std::memory_order_acquire);
    seen = started_.load(std::memory_order_acquire);
    if (stop_.load(std::memory_order_relaxed)) return;
    try {
      part_();
    } catch (...) {
      error_ = std::current_exception();
    }
    finished_.store(seen, std::memory_order_release);
    finished_.notify_one();
  }
}

}  // namespace naneye::app
