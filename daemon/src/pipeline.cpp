#include "naneye/daemon/pipeline.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <ctime>

namespace naneye::daemon {

std::int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

const char* to_string(ServiceState s) {
  switch (s) {
    case ServiceState::starting:
      return "starting";
    case ServiceState::streaming:
      return "streaming";
    case ServiceState::waiting_for_device:
      return "waiting_for_device";
    case ServiceState::stalled:
      return "stalled";
    case ServiceState::stopped:
      return "stopped";
  }
  return "unknown";
}

namespace {
std::shared_ptr<spdlog::logger> log() {
  auto l = spdlog::get("daemon");
  return l ? l : spdlog::default_logger();
}
}  // namespace

Pipeline::Pipeline(const Settings& settings, std::unique_ptr<PairProcessor> processor, SourceFactory factory,
                   SourceChoice choice, std::shared_ptr<const recon::StereoRig> rig)
    : settings_(settings),
      processor_(std::move(processor)),
      factory_(std::move(factory)),
      choice_(std::move(choice)),
      started_(std::chrono::steady_clock::now()),
      rig_(std::move(rig)),
      results_(settings.history + 2),
      // A PNG encode pins a frame slot for a few ms; four slots keep the worker from ever skipping.
      frames_(4),
      // A PNG of the map pins a slot for a few ms, /v1/depth/at for microseconds; a result's map is
      // looked up right after the result, so 4 slots keep it findable while pairs come at 62 fps.
      depth_maps_(4) {
  processor_->set_rig(*rig_);
  // Every buffer a result slot will hold, sized now: the worker then allocates nothing per pair.
  results_.prepare([this](Published& p) { processor_->reserve(p.scene, nullptr); });
  processor_->reserve(scratch_.scene, &depth_scratch_.map);
  if (processor_->dense())
    depth_maps_.prepare([this](DepthSlot& d) { processor_->reserve(scratch_.scene, &d.map); });
  rig_applied_ = rig_;
  processor_name_ = std::string(processor_->name());
}

Pipeline::~Pipeline() {
  stop();
}

void Pipeline::start() {
  open_source();
  worker_ = std::thread([this] { run(); });
}

void Pipeline::stop() {
  stop_.store(true);
  if (worker_.joinable()) worker_.join();
}

bool Pipeline::open_source() {
  try {
    auto src = factory_(choice_.uri);
    src->start();
    const auto info = src->info();
    {
      std::lock_guard lock(source_mu_);
      source_ = std::move(src);
    }
    opens_.fetch_add(1);
    waiting_.store(false);
    log()->info("source {} opened: kind {}, device \"{}\", {}", info.uri, info.kind, info.device,
                info.live ? "live (drops the oldest pair when behind)" : "replay (lossless)");
    return true;
  } catch (const std::exception& e) {
    const auto failures = open_failures_.fetch_add(1) + 1;
    if (failures == 1 || failures % 30 == 0) {
      log()->warn("source {} cannot be opened ({}); waiting for the device", choice_.uri, e.what());
    }
    waiting_.store(true);
    return false;
  }
}

void Pipeline::close_source() {
  std::unique_ptr<driver::FrameSource> old;
  {
    std::lock_guard lock(source_mu_);
    old = std::move(source_);
  }
  if (old) old->stop();
}

void Pipeline::reload_rig(std::shared_ptr<const recon::StereoRig> rig) {
  {
    std::lock_guard lock(rig_mu_);
    rig_ = std::move(rig);
  }
  rig_pending_.store(true);
}

void Pipeline::reload(std::shared_ptr<const recon::StereoRig> rig, std::unique_ptr<PairProcessor> prepared) {
  {
    std::lock_guard lock(rig_mu_);
    rig_ = std::move(rig);
    prepared_ = std::move(prepared);  // an earlier one not yet taken is replaced: the newest wins
  }
  rig_pending_.store(true);
}

void Pipeline::reload_refused(std::string reason) {
  reload_failures_.fetch_add(1);
  const double at = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  std::lock_guard lock(reload_mu_);
  last_reload_ = PipelineStatus::Reload{false, std::move(reason), at};
}

std::shared_ptr<const recon::StereoRig> Pipeline::rig() const {
  std::lock_guard lock(rig_mu_);
  return rig_;
}

bool Pipeline::source_finished() const {
  std::lock_guard lock(source_mu_);
  return source_ && source_->state() == driver::SourceState::finished;
}

void Pipeline::run() {
  auto backoff = std::chrono::milliseconds(100);
  auto next_open = std::chrono::steady_clock::now();
  while (!stop_.load()) {
    heartbeat_.fetch_add(1, std::memory_order_relaxed);
    if (rig_pending_.exchange(false)) {
      std::shared_ptr<const recon::StereoRig> next;
      std::unique_ptr<PairProcessor> prepared;
      {
        std::lock_guard lock(rig_mu_);
        next = rig_;
        prepared = std::move(prepared_);
      }
      try {
        if (prepared && prepared->name() == processor_name_) {
          processor_.swap(prepared);  // the previous one is freed when `prepared` goes
        } else {
          processor_->set_rig(*next);
        }
        rig_applied_ = next;
        reloads_.fetch_add(1);
        {
          const double at =
              std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
          std::lock_guard lock(reload_mu_);
          last_reload_ = PipelineStatus::Reload{true, "applied", at};
        }
        log()->info("calibration reloaded; the stream goes on");
      } catch (const std::exception& e) {
        // The last line behind rig_check: the worker must outlive any calibration it is given.
        // The processor is given its previous rig back, and HTTP readers see that one again.
        log()->error("calibration reload failed in the processing step, keeping the previous one: {}",
                     e.what());
        if (rig_applied_) {
          processor_->set_rig(*rig_applied_);
          std::lock_guard lock(rig_mu_);
          rig_ = rig_applied_;
        }
        reload_refused(std::string("the processing step refused it: ") + e.what());
      }
    }
    driver::FrameSource* src = source_.get();  // only this thread replaces source_
    if (!src) {
      if (std::chrono::steady_clock::now() >= next_open && !open_source()) {
        backoff = std::min(backoff * 2, std::chrono::milliseconds(2000));
        next_open = std::chrono::steady_clock::now() + backoff;
      }
      if (!source_) std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    auto pair = src->next(std::chrono::milliseconds(50));
    if (pair) {
      handle(std::move(pair));
      backoff = std::chrono::milliseconds(100);
      continue;
    }
    const auto st = src->state();
    if (st == driver::SourceState::failed) {
      // A source that gave up (as opposed to one reconnecting by itself): reopen it with backoff.
      log()->warn("source failed: {}; reopening", src->error().value_or("no detail"));
      close_source();
      waiting_.store(true);
      next_open = std::chrono::steady_clock::now() + backoff;
    } else if (st == driver::SourceState::finished || st == driver::SourceState::stopped) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  // Shutdown: stop the capture, then hand back (and publish) whatever the ring still held.
  std::unique_ptr<driver::FrameSource> src;
  {
    std::lock_guard lock(source_mu_);
    src = std::move(source_);
  }
  if (src) {
    src->stop();
    while (auto pair = src->next(std::chrono::milliseconds(0))) handle(std::move(pair));
    std::lock_guard lock(source_mu_);
    source_ = std::move(src);  // keep it for the final status (counters, state "stopped")
  }
}

void Pipeline::handle(driver::PairPtr pair) {
  Published* slot = results_.begin_write();
  const bool publishable = slot != nullptr;
  if (!publishable) slot = &scratch_;
  const auto seq = processed_.load(std::memory_order_relaxed) + 1;
  DepthSlot* depth = nullptr;
  if (processor_->dense()) {
    depth = depth_maps_.begin_write();
    if (!depth) depth = &depth_scratch_;  // every map pinned: computed (it is part of the result), not held
  }
  const std::int64_t t0 = monotonic_ns();
  processor_->process_pair(*pair, slot->result, slot->scene, depth ? &depth->map : nullptr);
  const std::int64_t t1 = monotonic_ns();
  if (depth && depth != &depth_scratch_) {
    depth->seq = seq;
    depth->pair = pair->index;
    // Published before the result that refers to it: a reader of result `seq` finds its map.
    if (slot->scene.dense)
      depth_maps_.publish(seq);
    else
      depth_maps_.abandon();
  }
  slot->seq = seq;
  slot->capture_ns = std::max(pair->left.host_ns, pair->right.host_ns);
  slot->recon_ns = t1 - t0;
  slot->published_ns = monotonic_ns();
  if (publishable) {
    results_.publish(seq);
  } else {
    skipped_.fetch_add(1, std::memory_order_relaxed);
  }
  processed_.store(seq, std::memory_order_relaxed);
  if (slot->scene.computed) {
    scene_pairs_.fetch_add(1, std::memory_order_relaxed);
    scene_valid_points_.fetch_add(static_cast<std::uint64_t>(slot->scene.sparse.valid_count),
                                  std::memory_order_relaxed);
    if (slot->scene.dense) dense_pairs_.fetch_add(1, std::memory_order_relaxed);
  }
  recon_latency_.record(t1 - t0);
  // host_ns is the arrival time on this host's monotonic clock; a replay that stamps recorded times
  // from another boot gives values that are not comparable, and those are left out.
  const std::int64_t since_capture = slot->published_ns - slot->capture_ns;
  if (slot->capture_ns > 0 && since_capture >= 0 && since_capture < 10'000'000'000) {
    capture_latency_.record(since_capture);
  }

  // Sensor frame rates from the sensors' own clocks: an exponential average of the frame period.
  // A period far above the average is a gap (a lost record, a replay looping), not a rate change,
  // unless it persists.
  auto update_fps = [](std::int64_t now, PeriodEstimate& e, std::atomic<double>& fps) {
    const bool first = e.last == kNoTime;
    const auto dt = static_cast<double>(first ? 0 : now - e.last);
    e.last = now;
    if (first || dt <= 0 || dt > 1e9) return;
    if (e.period > 0 && dt > 1.5 * e.period && ++e.rejected < 8) return;
    e.rejected = 0;
    e.period = e.period == 0 ? dt : 0.9 * e.period + 0.1 * dt;
    fps.store(1e9 / e.period, std::memory_order_relaxed);
  };
  update_fps(pair->left.sensor_ns, left_period_, fps_left_);
  update_fps(pair->right.sensor_ns, right_period_, fps_right_);
  offset_ns_.store(pair->offset_ns(), std::memory_order_relaxed);

  const std::int64_t interval = std::int64_t{settings_.frame_snapshot_interval_ms} * 1'000'000;
  if (slot->published_ns - last_frames_ns_ >= interval) {
    if (FrameSnapshot* f = frames_.begin_write()) {
      f->seq = seq;
      f->pair = pair->index;
      f->color = pair->left.color;
      f->left = pair->left.pixels;
      f->right = pair->right.pixels;
      f->corners = slot->result.point_count;
      for (int i = 0; i < f->corners; ++i) {
        f->left_px[static_cast<std::size_t>(i)] = slot->result.points[static_cast<std::size_t>(i)].left_px;
        f->right_px[static_cast<std::size_t>(i)] = slot->result.points[static_cast<std::size_t>(i)].right_px;
      }
      frames_.publish(seq);
      last_frames_ns_ = slot->published_ns;
    }
  }
}

PipelineStatus Pipeline::status() const {
  PipelineStatus s;
  s.choice = choice_;
  s.processor = processor_name_;
  s.pairs_processed = processed_.load(std::memory_order_relaxed);
  s.publish_skipped = skipped_.load(std::memory_order_relaxed);
  s.source_opens = opens_.load();
  s.source_open_failures = open_failures_.load();
  s.calibration_reloads = reloads_.load();
  s.calibration_reload_failures = reload_failures_.load();
  {
    std::lock_guard lock(reload_mu_);
    s.last_reload = last_reload_;
  }
  s.fps_left = fps_left_.load(std::memory_order_relaxed);
  s.fps_right = fps_right_.load(std::memory_order_relaxed);
  s.offset_ns = offset_ns_.load(std::memory_order_relaxed);
  s.recon = recon_latency_.snapshot();
  s.capture_to_publish = capture_latency_.snapshot();
  s.uptime_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  const std::int64_t now = monotonic_ns();
  results_.read_latest([&](const Published& p, std::uint64_t) {
    s.last_result_age_ms = static_cast<double>(now - p.published_ns) * 1e-6;
    if (!p.scene.computed) return;
    PipelineStatus::Scene sc;
    sc.features = static_cast<int>(p.scene.sparse.points.size());
    sc.valid_points = p.scene.sparse.valid_count;
    sc.noise_sigma_dn = p.scene.sparse.noise_sigma_dn;
    if (p.scene.dense) sc.depth = p.scene.depth;
    s.scene = sc;
  });
  s.scene_pairs = scene_pairs_.load(std::memory_order_relaxed);
  s.scene_valid_points = scene_valid_points_.load(std::memory_order_relaxed);
  s.dense_pairs = dense_pairs_.load(std::memory_order_relaxed);
  std::optional<driver::SourceState> src_state;
  {
    std::lock_guard lock(source_mu_);
    if (source_) {
      src_state = source_->state();
      s.info = source_->info();
      s.counters = source_->counters();
      s.source_error = source_->error();
    }
  }
  s.source_state =
      src_state ? driver::to_string(*src_state) : (waiting_.load() ? "waiting_for_device" : "none");
  if (stop_.load()) {
    s.state = ServiceState::stopped;
  } else if (!src_state || waiting_.load() || *src_state == driver::SourceState::waiting_for_device ||
             *src_state == driver::SourceState::failed) {
    s.state = ServiceState::waiting_for_device;
  } else if (*src_state == driver::SourceState::finished || *src_state == driver::SourceState::stopped) {
    s.state = ServiceState::stopped;
  } else if (*src_state == driver::SourceState::stalled) {
    s.state = ServiceState::stalled;
  } else if (!s.last_result_age_ms) {
    s.state = ServiceState::starting;
  } else if (*s.last_result_age_ms > settings_.stall_timeout_ms) {
    s.state = ServiceState::stalled;
  } else {
    s.state = ServiceState::streaming;
  }
  return s;
}

}  // namespace naneye::daemon
