#include "naneye/daemon/rig_reload.hpp"

#include "log.hpp"

namespace naneye::daemon {

RigReload::RigReload(std::shared_ptr<const recon::StereoRig> rig, const app::PairProcessor& processor,
                     std::chrono::steady_clock::time_point started)
    : started_(started), rig_(rig), applied_(std::move(rig)), name_(processor.name()) {}

double RigReload::uptime_s() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
}

void RigReload::offer(std::shared_ptr<const recon::StereoRig> rig,
                      std::unique_ptr<app::PairProcessor> prepared) {
  {
    std::lock_guard lock(mu_);
    rig_ = std::move(rig);
    prepared_ = std::move(prepared);
  }
  pending_.store(true);
}

void RigReload::refused(std::string reason) {
  failures_.fetch_add(1);
  const double at = uptime_s();
  std::lock_guard lock(outcome_mu_);
  last_ = PipelineStatus::Reload{false, std::move(reason), at};
}

std::shared_ptr<const recon::StereoRig> RigReload::rig() const {
  std::lock_guard lock(mu_);
  return rig_;
}

void RigReload::apply_pending(std::unique_ptr<app::PairProcessor>& processor) {
  if (!pending_.exchange(false)) return;
  std::shared_ptr<const recon::StereoRig> next;
  std::unique_ptr<app::PairProcessor> prepared;
  {
    std::lock_guard lock(mu_);
    next = rig_;
    prepared = std::move(prepared_);
  }
  try {
    if (prepared && prepared->scene() == processor->scene() && prepared->dense() == processor->dense()) {
      processor.swap(prepared);
      {
        std::lock_guard lock(outcome_mu_);
        name_ = processor->name();
      }
      std::lock_guard lock(mu_);
      if (!retired_) retired_ = std::move(prepared);  // else it is freed here: a storm outran release
    } else {
      processor->set_rig(*next);
    }
    applied_ = next;
    reloads_.fetch_add(1);
    {
      const double at = uptime_s();
      std::lock_guard lock(outcome_mu_);
      last_ = PipelineStatus::Reload{true, "applied", at};
    }
    log()->info("calibration reloaded; the stream goes on");
  } catch (const std::exception& e) {
    // The last line behind rig_check: the worker must outlive any calibration it is given.
    // The processor is given its previous rig back, and HTTP readers see that one again.
    log()->error("calibration reload failed in the processing step, keeping the previous one: {}", e.what());
    if (applied_) {
      processor->set_rig(*applied_);
      std::lock_guard lock(mu_);
      rig_ = applied_;
    }
    refused(std::string("the processing step refused it: ") + e.what());
  }
}

bool RigReload::release_retired() {
  std::unique_ptr<app::PairProcessor> old;
  {
    std::lock_guard lock(mu_);
    old = std::move(retired_);
  }
  return old != nullptr;  // freed here, outside the lock the worker may want
}

void RigReload::fill(PipelineStatus& s) const {
  s.calibration_reloads = reloads_.load();
  s.calibration_reload_failures = failures_.load();
  std::lock_guard lock(outcome_mu_);
  s.last_reload = last_;
  s.processor = name_;
}

}  // namespace naneye::daemon
