#pragma once
// RigReload: a new calibration handed from any thread (SIGHUP) to the worker, which applies it
// between two pairs. HTTP readers see the new rig at once (rig()); the worker swaps in a processor
// already set to it on the caller's thread (building the new maps never delays a pair), or sets
// its own. A prepared processor also brings what a SIGHUP reloads besides the calibration (the
// fixed pattern): its name, which says so, becomes the one /v1/status shows. A reload that fails in the
// processing step gives the processor, and readers, the previous rig back. Each outcome is kept for
// /v1/status (last, counts). The processor a swap replaces is not freed on the worker either: it waits for
// release_retired() on the caller's thread (freeing its maps and pools, and giving the pages back, costs a
// pair's time).
//
// Threads: offer(), refused(), rig(), release_retired() and fill() from any thread; apply_pending()
// is the worker's and takes the mutex only when a reload is pending.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "naneye/app/processor.hpp"
#include "naneye/daemon/pipeline_status.hpp"
#include "naneye/recon/camera/rig.hpp"

namespace naneye::daemon {

class RigReload {
 public:
  // `rig` is the one `processor` (named in the status) starts with; outcomes are stamped in seconds
  // since `started`.
  RigReload(std::shared_ptr<const recon::StereoRig> rig, const app::PairProcessor& processor,
            std::chrono::steady_clock::time_point started);

  // `prepared` (may be null) is a processor already set to `rig`; an earlier offer not yet taken is
  // replaced: the newest wins.
  void offer(std::shared_ptr<const recon::StereoRig> rig, std::unique_ptr<app::PairProcessor> prepared);
  // A reload refused before reaching the pipeline (or by the processing step); the rig in use stays.
  void refused(std::string reason);
  std::shared_ptr<const recon::StereoRig> rig() const;

  // Worker, between two pairs: applies a pending reload to `processor`. A prepared processor of
  // another kind (scene() or dense() differ: the result slots were sized for this one) is not
  // swapped in; `processor` is set to the rig instead.
  void apply_pending(std::unique_ptr<app::PairProcessor>& processor);
  // Frees the processor the last swap replaced, on the calling thread; true when there was one.
  // Should the worker swap again before this runs, it frees that second one itself.
  bool release_retired();
  // processor (the name of the one in use), calibration_reloads, calibration_reload_failures,
  // last_reload.
  void fill(PipelineStatus& s) const;

 private:
  double uptime_s() const;

  std::chrono::steady_clock::time_point started_;
  mutable std::mutex mu_;  // HTTP readers and reloads only; the worker takes it once per reload
  std::shared_ptr<const recon::StereoRig> rig_;
  std::unique_ptr<app::PairProcessor> prepared_;  // guarded by mu_: offer()'s, for the worker to take
  std::unique_ptr<app::PairProcessor> retired_;   // guarded by mu_: the worker's last swapped-out one
  std::atomic<bool> pending_{false};
  std::shared_ptr<const recon::StereoRig> applied_;  // worker only: the rig the processor has
  mutable std::mutex outcome_mu_;                    // guards last_ and name_ (changed by reloads)
  std::optional<PipelineStatus::Reload> last_;
  std::string name_;
  std::atomic<std::uint64_t> reloads_{0}, failures_{0};
};

}  // namespace naneye::daemon
