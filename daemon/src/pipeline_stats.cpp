#include "naneye/daemon/pipeline_stats.hpp"

#include "naneye/daemon/pipeline_status.hpp"

namespace naneye::daemon {

void PipelineStats::record(const Published& p, bool published, const driver::StereoPair& pair) {
  if (!published) skipped_.fetch_add(1, std::memory_order_relaxed);
  processed_.store(p.seq, std::memory_order_relaxed);
  if (p.scene.computed) {
    scene_pairs_.fetch_add(1, std::memory_order_relaxed);
    scene_valid_points_.fetch_add(static_cast<std::uint64_t>(p.scene.sparse.valid_count),
                                  std::memory_order_relaxed);
    if (p.scene.dense) dense_pairs_.fetch_add(1, std::memory_order_relaxed);
  }
  recon_latency_.record(p.recon_ns);
  // host_ns is the arrival time on this host's monotonic clock; a replay that stamps recorded times
  // from another boot gives values that are not comparable, and those are left out.
  const std::int64_t since_capture = p.published_ns - p.capture_ns;
  if (p.capture_ns > 0 && since_capture >= 0 && since_capture < 10'000'000'000) {
    capture_latency_.record(since_capture);
  }
  update_fps(pair.left.sensor_ns, pair.index, left_period_, fps_left_);
  update_fps(pair.right.sensor_ns, pair.index, right_period_, fps_right_);
  offset_ns_.store(pair.offset_ns(), std::memory_order_relaxed);
}

// Sensor frame rates from the sensors' own clocks: an exponential average of the frame period.
// The time between two processed pairs is shared by the pairs the source delivered in between
// (dropped by a full ring, or superseded by a newer pair while the worker was busy): the camera's
// rate, not the worker's. A period far above the average is a gap (a lost record, a replay
// looping), not a rate change, unless it persists.
void PipelineStats::update_fps(std::int64_t now, std::uint64_t index, PeriodEstimate& e,
                               std::atomic<double>& fps) {
  // A reopened source numbers its pairs from 0 again: a new start, like the first pair.
  const bool first = e.last == kNoTime || index <= e.last_index;
  const double dt = first ? 0 : static_cast<double>(now - e.last) / static_cast<double>(index - e.last_index);
  e.last = now;
  e.last_index = index;
  if (first || dt <= 0 || dt > 1e9) return;
  if (e.period > 0 && dt > 1.5 * e.period && ++e.rejected < 8) return;
  e.rejected = 0;
  e.period = e.period == 0 ? dt : 0.9 * e.period + 0.1 * dt;
  fps.store(1e9 / e.period, std::memory_order_relaxed);
}

void PipelineStats::fill(PipelineStatus& s) const {
  s.pairs_processed = processed_.load(std::memory_order_relaxed);
  s.publish_skipped = skipped_.load(std::memory_order_relaxed);
  s.pairs_superseded = superseded_.load(std::memory_order_relaxed);
  s.fps_left = fps_left_.load(std::memory_order_relaxed);
  s.fps_right = fps_right_.load(std::memory_order_relaxed);
  s.offset_ns = offset_ns_.load(std::memory_order_relaxed);
  s.recon = recon_latency_.snapshot();
  s.capture_to_publish = capture_latency_.snapshot();
  s.scene_pairs = scene_pairs_.load(std::memory_order_relaxed);
  s.scene_valid_points = scene_valid_points_.load(std::memory_order_relaxed);
  s.dense_pairs = dense_pairs_.load(std::memory_order_relaxed);
}

}  // namespace naneye::daemon
