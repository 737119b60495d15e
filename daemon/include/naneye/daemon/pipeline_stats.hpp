#pragma once
// PipelineStats: the worker's running figures for /v1/status and /metrics: pairs processed and not
// published, scene totals, the sensors' frame rates (from their own clocks) and offset, and the two
// latencies (processing, capture to publication). The worker calls record() once per pair and it
// neither allocates nor locks; any thread calls fill(). Each figure is a relaxed atomic on its own:
// a status is consistent enough, not a transaction.
#include <atomic>
#include <cstdint>

#include "naneye/daemon/latency.hpp"
#include "naneye/daemon/publication.hpp"
#include "naneye/driver/frame.hpp"

namespace naneye::daemon {

struct PipelineStatus;

class PipelineStats {
 public:
  // Worker: `p` was computed for `pair` (and `published`, or went to the scratch slot).
  void record(const Published& p, bool published, const driver::StereoPair& pair);
  std::uint64_t processed() const { return processed_.load(std::memory_order_relaxed); }
  // Worker: a live pair was skipped because a newer one waited behind it.
  void superseded() { superseded_.fetch_add(1, std::memory_order_relaxed); }
  // Any thread: the figures into `s` (pairs_processed, publish_skipped, superseded, fps, offset, latencies,
  // scene totals).
  void fill(PipelineStatus& s) const;

 private:
  static constexpr std::int64_t kNoTime = INT64_MIN;
  // An exponential average of one sensor's frame period.
  struct PeriodEstimate {
    std::int64_t last = kNoTime;
    std::uint64_t last_index = 0;  // the source's pair number at `last`
    double period = 0;             // ns
    int rejected = 0;
  };
  static void update_fps(std::int64_t sensor_ns, std::uint64_t index, PeriodEstimate& e,
                         std::atomic<double>& fps);

  std::atomic<std::uint64_t> processed_{0}, skipped_{0}, superseded_{0};
  std::atomic<std::uint64_t> scene_pairs_{0}, scene_valid_points_{0}, dense_pairs_{0};
  std::atomic<double> fps_left_{0}, fps_right_{0};
  std::atomic<std::int64_t> offset_ns_{0};
  PeriodEstimate left_period_, right_period_;  // worker only
  LatencyRecorder recon_latency_, capture_latency_;
};

}  // namespace naneye::daemon
