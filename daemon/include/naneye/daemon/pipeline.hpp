#pragma once
// The reconstruction worker: pulls pairs from the source (whose own capture thread fills its SPSC
// ring), runs the PairProcessor into a preallocated result slot and publishes it lock-free. HTTP
// threads read the published slots; nothing they do can make the worker wait.
//
// The worker's loop is all this class does; each of its jobs has its own part:
//   SourceSupervisor  (source_supervisor.hpp)  open, reopen with backoff, the source's state
//   Publication       (publication.hpp)        the pinned slots readers read, the hand-over into them
//   PipelineStats     (pipeline_stats.hpp)     pairs, frame rates, latencies, scene totals
//   RigReload         (rig_reload.hpp)         calibration hand-over between two pairs
// and status() gathers them into a PipelineStatus (pipeline_status.hpp).
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "naneye/app/processor.hpp"
#include "naneye/daemon/pipeline_stats.hpp"
#include "naneye/daemon/pipeline_status.hpp"
#include "naneye/daemon/publication.hpp"
#include "naneye/daemon/rig_reload.hpp"
#include "naneye/daemon/settings.hpp"
#include "naneye/daemon/source_supervisor.hpp"
#include "naneye/recon/camera/rig.hpp"

namespace naneye::daemon {

class Pipeline {
 public:
  Pipeline(const Settings& settings, std::unique_ptr<PairProcessor> processor, SourceOpener opener,
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
  // Frees, on the calling thread, the processor a reload replaced (the worker never frees one);
  // true when there was one. The reloading thread calls it after its reload has been applied.
  bool release_retired_processor() { return reload_.release_retired(); }
  std::shared_ptr<const recon::StereoRig> rig() const { return reload_.rig(); }

  const PinnedSlots<Published>& results() const { return publication_.results(); }
  const PinnedSlots<FrameSnapshot>& frames() const { return publication_.frames(); }
  // The latest dense maps, each tagged with its result's sequence number (depth_map(seq) finds the
  // one of a given result, if it is still held).
  const PinnedSlots<DepthSlot>& depth_maps() const { return publication_.depth_maps(); }
  PipelineStatus status() const;
  // Worker loop iterations: advances while the worker is alive, pairs or not.
  std::uint64_t heartbeat() const { return heartbeat_.load(std::memory_order_relaxed); }
  std::uint64_t pairs_processed() const { return stats_.processed(); }

 private:
  void run();
  void handle(driver::PairPtr pair);

  Settings settings_;
  std::chrono::steady_clock::time_point started_;
  std::unique_ptr<PairProcessor> processor_;  // worker only (swapped by reload_ between pairs)
  SourceSupervisor source_;
  RigReload reload_;
  Publication publication_;
  PipelineStats stats_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> heartbeat_{0};
  std::thread worker_;
};

}  // namespace naneye::daemon
