#pragma once
// SourceSupervisor: keeps the pipeline's source open. It opens the chosen URI through a SourceOpener;
// while that fails, and after the source gives up (state failed), it retries with base::Backoff
// (delays, "say why once" logging, the open counters /v1/status and /metrics show), meanwhile
// reporting waiting_for_device. A source that reconnects by itself (usb://, v4l2://) is left to do
// so. It does nothing per pair but hand out the open source.
//
// Threads: the worker calls ready(), healthy(), idle() and finish(), and is the only one to replace
// the source; any thread calls snapshot() (the mutex it takes is never taken per pair).
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "naneye/base/backoff.hpp"
#include "naneye/driver/frame_source.hpp"

namespace naneye::daemon {

// Opens a source for a URI (the driver's registry in naneyed); throws driver::SourceError. Not
// driver::SourceFactory (one scheme's factory, given the parsed URI): this one takes any URI.
using SourceOpener = std::function<std::unique_ptr<driver::FrameSource>(const std::string& uri)>;

// Where the source came from (for "auto", which device or which fallback capture, and why).
struct SourceChoice {
  std::string uri;
  std::string reason;
  bool fallback = false;  // "auto" found no readout board and fell back to the sample capture
};

class SourceSupervisor {
 public:
  // The pipeline's delays: from 100 ms up to 2 s (a replay or a board coming back is seen soon).
  static constexpr base::BackoffSettings kBackoff{.initial_ms = 100, .factor = 2.0, .max_ms = 2000};

  SourceSupervisor(SourceOpener opener, SourceChoice choice);

  // One open attempt now; false (and waiting) when it failed.
  bool open();
  // Worker: the open source, or null when there is none (an open is tried when its delay is up,
  // else the call sleeps ~20 ms).
  driver::FrameSource* ready();
  // Worker: whether the open source is live (drops its oldest pair when the worker is behind) rather
  // than a lossless replay; read once when it opened (info() copies strings).
  bool live() const { return live_; }
  // Worker: a pair came, the source works: the next delay starts from the shortest again.
  void healthy() { backoff_.reset(); }
  // Worker: next() gave nothing. A source that failed is closed and reopened after a delay; one that
  // finished or stopped is kept (its final state and counters stay visible), with a ~20 ms sleep.
  void idle();
  // Worker, at shutdown: stops the source and hands every pair its ring still holds to `each`; the
  // source is kept for the final status (counters, state stopped).
  void finish(const std::function<void(driver::PairPtr)>& each);

  struct Snapshot {
    std::optional<driver::SourceState> state;  // empty when no source is open
    std::optional<driver::SourceInfo> info;
    driver::SourceCounters counters;
    std::optional<std::string> error;
    bool waiting = false;  // the last open failed, or the source failed and waits to be reopened
    std::uint64_t opens = 0, open_failures = 0;
  };
  Snapshot snapshot() const;  // any thread
  const SourceChoice& choice() const { return choice_; }

 private:
  void close();

  SourceOpener opener_;
  SourceChoice choice_;
  base::Backoff backoff_;  // opens = its successes, open failures = its failures
  std::chrono::steady_clock::time_point next_open_{};
  mutable std::mutex mu_;  // guards replacing source_ against snapshot()
  std::unique_ptr<driver::FrameSource> source_;
  std::atomic<bool> waiting_{false};
  bool live_ = true;  // worker only
};

}  // namespace naneye::daemon
