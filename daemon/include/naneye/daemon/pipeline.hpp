#pragma once
// The reconstruction worker: pulls pairs from the source (whose own capture thread fills its SPSC
// ring), runs the PairProcessor into a preallocated result slot and publishes it lock-free. HTTP
// threads read the published slots; nothing they do can make the worker wait.
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "naneye/app/processor.hpp"
#include "naneye/daemon/latency.hpp"
#include "naneye/daemon/pinned_slots.hpp"
#include "naneye/daemon/settings.hpp"
#include "naneye/driver/frame_source.hpp"
#include "naneye/recon/camera/rig.hpp"

namespace naneye::daemon {

// Opens a source for a URI (the driver's registry in naneyed); throws driver::SourceError.
using SourceFactory = std::function<std::unique_ptr<driver::FrameSource>(const std::string& uri)>;

// One published result with the times the service adds to it.
struct Published {
  recon::PairResult result;
  SceneResult scene;              // empty (computed = false) in [recon] mode board
  std::uint64_t seq = 0;          // 1, 2, 3... per processed pair: the /v1/events id
  std::int64_t capture_ns = 0;    // CLOCK_MONOTONIC when the pair's last record arrived
  std::int64_t published_ns = 0;  // CLOCK_MONOTONIC when it was published
  std::int64_t recon_ns = 0;      // time spent in the processor
};

// The latest frames, copied every frame_snapshot_interval_ms for /v1/frames (not every pair).
struct FrameSnapshot {
  std::uint64_t seq = 0, pair = 0;
  driver::ColorMode color = driver::ColorMode::mono;
  std::array<std::uint16_t, driver::kPixelCount> left{}, right{};
  int corners = 0;
  std::array<Eigen::Vector2d, recon::kMaxCorners> left_px{}, right_px{};
};

enum class ServiceState { starting, streaming, waiting_for_device, stalled, stopped };
const char* to_string(ServiceState s);

// Where the source came from (for "auto", which device or which fallback capture, and why).
struct SourceChoice {
  std::string uri;
  std::string reason;
  bool fallback = false;  // "auto" found no readout board and fell back to the sample capture
};

// A consistent-enough copy of everything /v1/status, /metrics and the watchdog report.
struct PipelineStatus {
  ServiceState state = ServiceState::starting;
  std::string source_state = "none";
  std::optional<driver::SourceInfo> info;
  driver::SourceCounters counters;
  std::optional<std::string> source_error;
  SourceChoice choice;
  std::string processor;
  std::uint64_t pairs_processed = 0;
  std::uint64_t publish_skipped = 0;  // every slot pinned by readers: result computed, not published
  std::uint64_t source_opens = 0, source_open_failures = 0;
  std::uint64_t calibration_reloads = 0;
  std::uint64_t calibration_reload_failures = 0;
  // The outcome of the latest reload request (SIGHUP), if any: the calibration in use is the old
  // one whenever it failed.
  struct Reload {
    bool ok = false;
    std::string reason;      // "applied", or why the new calibration was refused
    double at_uptime_s = 0;  // when it was decided
  };
  std::optional<Reload> last_reload;
  double fps_left = 0, fps_right = 0;
  std::int64_t offset_ns = 0;
  std::optional<double> last_result_age_ms;
  LatencyRecorder::Snapshot recon, capture_to_publish;
  double uptime_s = 0;
  // The latest result's scene ([recon] mode scene or both; empty in mode board or before a result).
  struct Scene {
    int features = 0, valid_points = 0;
    double noise_sigma_dn = 0;
    std::optional<DepthSummary> depth;  // empty without a dense map
  };
  std::optional<Scene> scene;
  std::uint64_t scene_pairs = 0, scene_valid_points = 0, dense_pairs = 0;  // totals since the start
};

class Pipeline {
 public:
  Pipeline(const Settings& settings, std::unique_ptr<PairProcessor> processor, SourceFactory factory,
           SourceChoice choice, std::shared_ptr<const recon::StereoRig> rig);
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  // Opens the source (a failure to open is "waiting_for_device", retried with backoff) and starts
  // the worker. Returns once the first open attempt is done.
  void start();
  // Stops the source, processes what its ring still holds, joins the worker. Idempotent.
  void stop();

  // From any thread: the worker switches to `rig` between two pairs; HTTP readers see it at once.
  void reload_rig(std::shared_ptr<const recon::StereoRig> rig);
  // The same with a processor already set to `rig` on the caller's thread (make_processor, then
  // set_rig): the worker only swaps it in between two pairs, so building the new maps never delays
  // a pair (a SIGHUP storm made a live source drop pairs while the worker rebuilt them).
  void reload(std::shared_ptr<const recon::StereoRig> rig, std::unique_ptr<PairProcessor> prepared);
  // Records a reload that was refused before reaching the pipeline (unreadable, or not valid for
  // the sensor: rig_check.hpp); the rig in use stays.
  void reload_refused(std::string reason);
  std::shared_ptr<const recon::StereoRig> rig() const;

  const PinnedSlots<Published>& results() const { return results_; }
  const PinnedSlots<FrameSnapshot>& frames() const { return frames_; }
  // The latest dense maps, each tagged with its result's sequence number (depth_map(seq) finds the
  // one of a given result, if it is still held).
  const PinnedSlots<DepthSlot>& depth_maps() const { return depth_maps_; }
  PipelineStatus status() const;
  // Worker loop iterations: advances while the worker is alive, pairs or not.
  std::uint64_t heartbeat() const { return heartbeat_.load(std::memory_order_relaxed); }
  std::uint64_t pairs_processed() const { return processed_.load(std::memory_order_relaxed); }
  bool source_finished() const;

 private:
  void run();
  bool open_source();
  void handle(driver::PairPtr pair);
  void close_source();

  Settings settings_;
  std::unique_ptr<PairProcessor> processor_;
  SourceFactory factory_;
  SourceChoice choice_;
  std::chrono::steady_clock::time_point started_;

  mutable std::mutex source_mu_;  // guards replacing source_ against status(); never taken per pair
  std::unique_ptr<driver::FrameSource> source_;

  mutable std::mutex rig_mu_;  // HTTP readers and reloads only; the worker takes it once per reload
  std::shared_ptr<const recon::StereoRig> rig_;
  std::atomic<bool> rig_pending_{false};
  std::unique_ptr<PairProcessor> prepared_;  // guarded by rig_mu_: reload()'s, for the worker to take
  std::shared_ptr<const recon::StereoRig> rig_applied_;  // worker only: the rig the processor has
  std::string processor_name_;                           // fixed: every processor comes from the settings
  mutable std::mutex reload_mu_;                         // guards last_reload_ (a reload's outcome, rare)
  std::optional<PipelineStatus::Reload> last_reload_;
  std::atomic<std::uint64_t> reload_failures_{0};

  PinnedSlots<Published> results_;
  PinnedSlots<FrameSnapshot> frames_;
  PinnedSlots<DepthSlot> depth_maps_;
  Published scratch_;        // used when every slot is pinned, so processing never waits
  DepthSlot depth_scratch_;  // the same for the dense map

  std::atomic<bool> stop_{false};
  std::thread worker_;
  std::atomic<std::uint64_t> heartbeat_{0}, processed_{0}, skipped_{0}, opens_{0}, open_failures_{0},
      reloads_{0};
  std::atomic<std::uint64_t> scene_pairs_{0}, scene_valid_points_{0}, dense_pairs_{0};
  std::atomic<double> fps_left_{0}, fps_right_{0};
  std::atomic<std::int64_t> offset_ns_{0};
  std::atomic<bool> waiting_{false};
  static constexpr std::int64_t kNoTime = INT64_MIN;
  struct PeriodEstimate {
    std::int64_t last = kNoTime;
    double period = 0;  // ns
    int rejected = 0;
  };
  PeriodEstimate left_period_, right_period_;  // worker only
  std::int64_t last_frames_ns_ = 0;            // worker only
  LatencyRecorder recon_latency_, capture_latency_;
};

std::int64_t monotonic_ns();

}  // namespace naneye::daemon
