#include "naneye/daemon/pipeline.hpp"

#include <algorithm>

#include "naneye/base/clock.hpp"

namespace naneye::daemon {
namespace {

// The processor set to its first rig before any slot is sized (reserve() may depend on it).
std::unique_ptr<PairProcessor> with_rig(std::unique_ptr<PairProcessor> p, const recon::StereoRig& rig) {
  p->set_rig(rig);
  return p;
}

}  // namespace

Pipeline::Pipeline(const Settings& settings, std::unique_ptr<PairProcessor> processor, SourceOpener opener,
                   SourceChoice choice, std::shared_ptr<const recon::StereoRig> rig)
    : settings_(settings),
      started_(std::chrono::steady_clock::now()),
      processor_(with_rig(std::move(processor), *rig)),
      source_(std::move(opener), std::move(choice)),
      reload_(std::move(rig), *processor_, started_),
      // Every buffer a result slot will hold, sized now: the worker then allocates nothing per pair.
      publication_(static_cast<std::size_t>(settings.history), settings.frame_snapshot_interval_ms,
                   *processor_) {}

Pipeline::~Pipeline() {
  stop();
}

void Pipeline::start() {
  source_.open();
  worker_ = std::thread([this] { run(); });
}

void Pipeline::stop() {
  stop_.store(true);
  if (worker_.joinable()) worker_.join();
}

void Pipeline::reload_rig(std::shared_ptr<const recon::StereoRig> rig) {
  reload_.offer(std::move(rig), nullptr);
}

void Pipeline::reload(std::shared_ptr<const recon::StereoRig> rig, std::unique_ptr<PairProcessor> prepared) {
  reload_.offer(std::move(rig), std::move(prepared));
}

void Pipeline::reload_refused(std::string reason) {
  reload_.refused(std::move(reason));
}

void Pipeline::run() {
  while (!stop_.load()) {
    heartbeat_.fetch_add(1, std::memory_order_relaxed);
    reload_.apply_pending(processor_);
    driver::FrameSource* src = source_.ready();
    if (!src) continue;
    if (auto pair = src->next(std::chrono::milliseconds(50))) {
      // A live source's ring is a hand-over, not a queue: when pairs wait behind this one the worker
      // is slower than the camera, and processing them in order would publish each one as late as
      // the ring is long (155-173 ms with 8 pairs in scene mode, docs/http-api.md). The newest is
      // the one a client asks about; the older ones go back to the pool, superseded (recording
      // taps the bytes on the capture thread and loses nothing). A lossless replay keeps its order.
      if (source_.live()) {
        while (auto newer = src->next(std::chrono::milliseconds(0))) {
          stats_.superseded();
          pair = std::move(newer);
        }
      }
      handle(std::move(pair));
      source_.healthy();
      continue;
    }
    source_.idle();
  }
  // Shutdown: stop the capture, then hand back (and publish) whatever the ring still held.
  source_.finish([this](driver::PairPtr pair) { handle(std::move(pair)); });
}

void Pipeline::handle(driver::PairPtr pair) {
  const auto w = publication_.begin(processor_->dense());
  Published& out = *w.result;
  const std::int64_t t0 = base::monotonic_ns();
  processor_->process_pair(*pair, out.result, out.scene, w.depth ? &w.depth->map : nullptr);
  out.recon_ns = base::monotonic_ns() - t0;
  out.capture_ns = std::max(pair->left.host_ns, pair->right.host_ns);
  const bool published = publication_.publish(w, stats_.processed() + 1, pair->index);
  stats_.record(out, published, *pair);
  publication_.offer_frames(out, *pair);
}

PipelineStatus Pipeline::status() const {
  PipelineStatus s;
  s.choice = source_.choice();
  stats_.fill(s);
  reload_.fill(s);
  s.uptime_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  const std::int64_t now = base::monotonic_ns();
  publication_.results().read_latest([&](const Published& p, std::uint64_t) {
    s.last_result_age_ms = static_cast<double>(now - p.published_ns) * 1e-6;
    if (!p.scene.computed) return;
    PipelineStatus::Scene sc;
    sc.features = static_cast<int>(p.scene.sparse.points.size());
    sc.valid_points = p.scene.sparse.valid_count;
    sc.noise_sigma_dn = p.scene.sparse.noise_sigma_dn;
    if (p.scene.dense) sc.depth = p.scene.depth;
    s.scene = sc;
  });
  const auto src = source_.snapshot();
  s.info = src.info;
  s.counters = src.counters;
  s.source_error = src.error;
  s.source_opens = src.opens;
  s.source_open_failures = src.open_failures;
  s.source_state = src.state ? driver::to_string(*src.state) : (src.waiting ? "waiting_for_device" : "none");
  s.state =
      service_state(stop_.load(), src.state, src.waiting, s.last_result_age_ms, settings_.stall_timeout_ms);
  return s;
}

}  // namespace naneye::daemon
