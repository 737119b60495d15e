#pragma once
// What /v1/status, /metrics and the watchdog read of the pipeline: one consistent-enough copy,
// gathered by Pipeline::status() from its parts (source supervision, statistics, reloads,
// publication), and the service state derived from it.
#include <cstdint>
#include <optional>
#include <string>

#include "naneye/app/scene_result.hpp"
#include "naneye/daemon/latency.hpp"
#include "naneye/daemon/source_supervisor.hpp"
#include "naneye/driver/frame_source.hpp"

namespace naneye::daemon {

enum class ServiceState { starting, streaming, waiting_for_device, stalled, stopped };
const char* to_string(ServiceState s);

struct PipelineStatus {
  ServiceState state = ServiceState::starting;
  std::string source_state = "none";
  std::optional<driver::SourceInfo> info;
  driver::SourceCounters counters;
  std::optional<std::string> source_error;
  SourceChoice choice;
  std::string processor;
  std::uint64_t pairs_processed = 0;
  std::uint64_t publish_skipped = 0;   // every slot pinned by readers: result computed, not published
  std::uint64_t pairs_superseded = 0;  // live pairs not processed: a newer one waited behind them
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
    std::optional<app::DepthSummary> depth;  // empty without a dense map
  };
  std::optional<Scene> scene;
  std::uint64_t scene_pairs = 0, scene_valid_points = 0, dense_pairs = 0;  // totals since the start
};

// The service state from the source's (empty: none open), whether the supervisor waits for it,
// the latest result's age and the stall timeout; `stopping` wins over everything.
ServiceState service_state(bool stopping, std::optional<driver::SourceState> source, bool waiting,
                           std::optional<double> last_result_age_ms, int stall_timeout_ms);

}  // namespace naneye::daemon
