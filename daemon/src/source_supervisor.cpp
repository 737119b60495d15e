#include "naneye/daemon/source_supervisor.hpp"

#include <thread>

#include "log.hpp"

namespace naneye::daemon {
namespace {

constexpr auto kIdleSleep = std::chrono::milliseconds(20);

}  // namespace

SourceSupervisor::SourceSupervisor(SourceOpener opener, SourceChoice choice)
    : opener_(std::move(opener)),
      choice_(std::move(choice)),
      backoff_(kBackoff, log(), "source " + choice_.uri) {}

bool SourceSupervisor::open() {
  try {
    auto src = opener_(choice_.uri);
    src->start();
    const auto info = src->info();
    live_ = info.live;
    {
      std::lock_guard lock(mu_);
      source_ = std::move(src);
    }
    waiting_.store(false);
    backoff_.succeeded();
    log()->info("source {} opened: kind {}, device \"{}\", {}", info.uri, info.kind, info.device,
                info.live ? "live (drops the oldest pair when behind)" : "replay (lossless)");
    return true;
  } catch (const std::exception& e) {
    next_open_ =
        std::chrono::steady_clock::now() + backoff_.failed(std::string("cannot be opened: ") + e.what());
    waiting_.store(true);
    return false;
  }
}

driver::FrameSource* SourceSupervisor::ready() {
  if (source_) return source_.get();  // only this thread replaces source_
  if (std::chrono::steady_clock::now() >= next_open_ && open()) return source_.get();
  std::this_thread::sleep_for(kIdleSleep);
  return nullptr;
}

void SourceSupervisor::idle() {
  const auto st = source_->state();
  if (st == driver::SourceState::failed) {
    // A source that gave up (as opposed to one reconnecting by itself): reopen it with backoff.
    const auto delay = backoff_.lost("failed: " + source_->error().value_or("no detail"));
    close();
    waiting_.store(true);
    next_open_ = std::chrono::steady_clock::now() + delay;
  } else if (st == driver::SourceState::finished || st == driver::SourceState::stopped) {
    std::this_thread::sleep_for(kIdleSleep);
  }
}

void SourceSupervisor::close() {
  std::unique_ptr<driver::FrameSource> old;
  {
    std::lock_guard lock(mu_);
    old = std::move(source_);
  }
  if (old) old->stop();
}

void SourceSupervisor::finish(const std::function<void(driver::PairPtr)>& each) {
  std::unique_ptr<driver::FrameSource> src;
  {
    std::lock_guard lock(mu_);
    src = std::move(source_);
  }
  if (!src) return;
  src->stop();
  while (auto pair = src->next(std::chrono::milliseconds(0))) each(std::move(pair));
  std::lock_guard lock(mu_);
  source_ = std::move(src);
}

SourceSupervisor::Snapshot SourceSupervisor::snapshot() const {
  Snapshot s;
  const auto b = backoff_.counters();
  s.opens = b.successes;
  s.open_failures = b.failures;
  s.waiting = waiting_.load();
  std::lock_guard lock(mu_);
  if (source_) {
    s.state = source_->state();
    s.info = source_->info();
    s.counters = source_->counters();
    s.error = source_->error();
  }
  return s;
}

}  // namespace naneye::daemon
