#pragma once
// Backoff: reconnect-with-delay, the one policy behind usb://, v4l2:// and the daemon's source
// supervisor (each keeps only its own settings).
//
// Delays: next_delay() returns the delay to wait before the next try and grows the one after it by
// `factor`, up to `max_ms`; reset() goes back to `initial_ms` (the caller's "it works again").
//
// "Say why once" (ustreamer's rule), on the logger given: the first failure of an outage is logged at
// warn with its reason; the same reason again goes to debug; a different reason is logged at warn
// again; the end of an outage (succeeded()) is logged once at info, with how long it lasted and how
// many attempts it took. An outage starts with lost() or with the first failed() outside one.
//
// Threads: one thread (the one that reconnects) calls everything but counters(), which any thread
// may call (the counters are atomics).
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

namespace naneye::base {

struct BackoffSettings {
  int initial_ms = 100;  // the delay before the first retry
  double factor = 2.0;   // each failure multiplies the delay by this
  int max_ms = 5000;     // ... up to this
};

struct BackoffCounters {
  std::uint64_t attempts = 0;    // failed() + succeeded()
  std::uint64_t failures = 0;    // failed()
  std::uint64_t successes = 0;   // succeeded()
  std::uint64_t recoveries = 0;  // successes after the first: reconnections
  std::uint64_t losses = 0;      // lost()
};

class Backoff {
 public:
  // `what` starts every line logged ("usb", "v4l2 /dev/video0", "source file:///x.neyd").
  Backoff(BackoffSettings settings, std::shared_ptr<spdlog::logger> log, std::string what);

  // The delay to wait now; the next one grows by `factor`, up to `max_ms`.
  std::chrono::milliseconds next_delay();
  // The delay goes back to `initial_ms`.
  void reset();

  // An attempt failed for `reason`: counted and logged (see above). Returns next_delay().
  std::chrono::milliseconds failed(std::string_view reason);
  // An attempt worked: counted; an outage, if any, ends and is logged. The delay is left as it is
  // (reset() when the caller deems the link healthy: at once, or at its first data).
  void succeeded();
  // The link was lost (device gone, source failed): starts an outage, logged at warn with the
  // reason. Returns next_delay().
  std::chrono::milliseconds lost(std::string_view reason);

  bool in_outage() const { return in_outage_; }
  BackoffCounters counters() const;
  const BackoffSettings& settings() const { return s_; }

 private:
  void start_outage();

  BackoffSettings s_;
  std::shared_ptr<spdlog::logger> log_;
  std::string what_;
  double delay_ms_;
  bool in_outage_ = false;
  std::string told_;  // the reason last logged at warn in this outage
  std::uint64_t outage_attempts_ = 0;
  std::chrono::steady_clock::time_point outage_start_{};
  std::atomic<std::uint64_t> attempts_{0}, failures_{0}, successes_{0}, recoveries_{0}, losses_{0};
};

}  // namespace naneye::base
