// The pipeline in-process: a real file:// source at max speed, the worker, and HTTP-like readers
// hammering the publication at the same time. Part of test_daemon_tsan.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <functional>
#include <thread>

#include "capture.hpp"
#include "naneye/app/processor.hpp"
#include "naneye/daemon/pipeline.hpp"
#include "naneye/daemon/source_select.hpp"
#include "naneye/recon/camera/calibration_io.hpp"
#include "scene_capture.hpp"
#include "temp_dir.hpp"

using namespace naneye;
using namespace naneye::daemon::test;

namespace {

std::shared_ptr<const recon::StereoRig> paper_rig() {
  return std::make_shared<const recon::StereoRig>(
      recon::load_rig(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml"));
}

// A pipeline on a file:// replay of `file` (`query`: its parameters), the driver's sources and the
// paper's rig.
std::unique_ptr<daemon::Pipeline> replay_pipeline(const daemon::Settings& settings,
                                                  const std::filesystem::path& file,
                                                  const std::string& query) {
  return std::make_unique<daemon::Pipeline>(
      settings, app::make_processor(settings.processor), daemon::driver_source_factory(),
      daemon::SourceChoice{"file://" + file.string() + "?" + query, "test", false}, paper_rig());
}

// Starts the pipeline and runs `reader` on two threads (each until `done`) while it processes `n`
// pairs (or `timeout` passes); returns once the readers are joined.
void process_while_reading(daemon::Pipeline& pipeline, std::uint64_t n, std::chrono::seconds timeout,
                           const std::function<void(const std::atomic<bool>& done)>& reader) {
  std::atomic<bool> done{false};
  pipeline.start();
  std::thread a([&] { reader(done); }), b([&] { reader(done); });
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (pipeline.pairs_processed() < n && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  done.store(true);
  a.join();
  b.join();
}

}  // namespace

TEST(Pipeline, PublishesEveryPairOfALosslessReplayWhileReadersRead) {
  TempDir dir;
  const int n = 60;
  const auto truth = write_capture(dir.path / "c.raw", n);
  daemon::Settings settings;
  settings.processor.detect =
      false;  // the hand-over and publication are under test, on frames without a board
  settings.history = 128;
  settings.frame_snapshot_interval_ms = 0;  // every pair: the most contention on the frame slots
  const auto pipeline = replay_pipeline(settings, dir.path / "c.raw", "speed=max");
  std::atomic<int> bad{0}, reads{0};
  auto reader = [&](const std::atomic<bool>& done) {
    std::uint64_t last = 0;
    while (!done.load()) {
      pipeline->results().read_latest([&](const daemon::Published& p, std::uint64_t seq) {
        bad += p.seq != seq || seq < last || p.result.pair + 1 != seq ||
               p.result.t_right_ns - p.result.t_left_ns != truth.offset_ns();
        last = seq;
        ++reads;
      });
      pipeline->frames().read_latest([&](const daemon::FrameSnapshot& f, std::uint64_t) {
        const int k = static_cast<int>(f.pair % n);
        for (int r : {1, 77, 200})
          for (int c : {5, 120, 248}) {
            bad += f.left[static_cast<std::size_t>(r) * 250 + c] != pixel(k, 0, r, c);
            bad += f.right[static_cast<std::size_t>(r) * 250 + c] != pixel(k, 1, r, c);
          }
      });
      (void)pipeline->status();
    }
  };
  process_while_reading(*pipeline, n, std::chrono::seconds(20), reader);
  ASSERT_EQ(pipeline->pairs_processed(), static_cast<std::uint64_t>(n));
  EXPECT_EQ(bad.load(), 0);
  EXPECT_GT(reads.load(), 0);
  // Every result is still held, in order, each the pair it claims to be.
  for (std::uint64_t seq = 1; seq <= static_cast<std::uint64_t>(n); ++seq) {
    EXPECT_TRUE(pipeline->results().read_seq(seq, [&](const daemon::Published& p) {
      EXPECT_EQ(p.result.pair, seq - 1);
      EXPECT_GE(p.published_ns, p.capture_ns);
    })) << seq;
  }
  const auto st = pipeline->status();
  EXPECT_EQ(st.counters.pairs_dropped, 0u);
  EXPECT_EQ(st.publish_skipped, 0u);
  EXPECT_NEAR(st.fps_left, truth.fps(), 0.01);
  EXPECT_EQ(st.offset_ns, truth.offset_ns());
  EXPECT_EQ(st.recon.count, static_cast<std::uint64_t>(n));
  pipeline->stop();
  EXPECT_EQ(pipeline->status().state, daemon::ServiceState::stopped);
}

// The real processing step, made slower than the camera (a scene-mode worker on a slow machine):
// every pair takes `cost` more.
class SlowProcessor : public app::PairProcessor {
 public:
  SlowProcessor(std::unique_ptr<app::PairProcessor> inner, std::chrono::milliseconds cost)
      : inner_(std::move(inner)), cost_(cost) {}
  void set_rig(const recon::StereoRig& rig) override { inner_->set_rig(rig); }
  void process(const driver::StereoPair& pair, recon::PairResult& out) override {
    std::this_thread::sleep_for(cost_);
    inner_->process(pair, out);
  }
  std::string_view name() const override { return "slow"; }

 private:
  std::unique_ptr<app::PairProcessor> inner_;
  std::chrono::milliseconds cost_;
};

// A live source (a replay at the recorded 62 fps: drop-oldest) and a worker at 40 ms per pair,
// 2.5 camera periods: the worker takes the newest pair waiting, so each result is one pair's
// processing old when it is published, not the ring's eight pairs behind (in order, the p50 from
// capture to publication was ~170 ms here, 8 x 16 ms + 40 ms). Nothing goes unaccounted: every pair
// the source delivered was processed, superseded or dropped by the full ring.
TEST(Pipeline, ALiveSourceFasterThanTheWorkerGetsItsNewestPairProcessed) {
  TempDir dir;
  const int n = 60;  // ~1 s at 62 fps
  write_capture(dir.path / "c.raw", n);
  daemon::Settings settings;
  settings.processor.detect = false;
  daemon::Pipeline pipeline(
      settings,
      std::make_unique<SlowProcessor>(app::make_processor(settings.processor), std::chrono::milliseconds(40)),
      daemon::driver_source_factory(),
      daemon::SourceChoice{"file://" + (dir.path / "c.raw").string() + "?speed=realtime", "test", false},
      paper_rig());
  pipeline.start();
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (pipeline.status().source_state != "finished" && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  pipeline.stop();
  const auto st = pipeline.status();
  EXPECT_EQ(st.counters.pairs, static_cast<std::uint64_t>(n));
  EXPECT_EQ(st.pairs_processed + st.pairs_superseded + st.counters.pairs_dropped, st.counters.pairs);
  EXPECT_GT(st.pairs_superseded, 0u);
  // The camera's rate, though the worker saw every third pair or so.
  EXPECT_NEAR(st.fps_left, 62.0, 0.1);
  // Published in capture order, the pair numbers increasing.
  std::uint64_t last_pair = 0;
  int in_order = 0;
  for (std::uint64_t seq = 1; seq <= st.pairs_processed; ++seq) {
    pipeline.results().read_seq(seq, [&](const daemon::Published& p) {
      in_order += seq == 1 || p.result.pair > last_pair;
      last_pair = p.result.pair;
    });
  }
  EXPECT_EQ(in_order, static_cast<int>(st.pairs_processed));
  std::printf(
      "live 62 fps, 40 ms per pair: %llu processed, %llu superseded, %llu dropped; capture to "
      "publication p50 %.1f ms, max %.1f ms\n",
      static_cast<unsigned long long>(st.pairs_processed),
      static_cast<unsigned long long>(st.pairs_superseded),
      static_cast<unsigned long long>(st.counters.pairs_dropped), st.capture_to_publish.p50_ms,
      st.capture_to_publish.max_ms);
  // One processing time plus up to a camera period (and the replay's own pacing): 40-60 ms. In
  // order it would be the ring's eight periods more (161 ms measured); 120 ms leaves room for a
  // loaded machine's wake-ups and still tells the two apart.
  EXPECT_LT(st.capture_to_publish.p50_ms, 120.0);
}

TEST(Pipeline, ReloadsTheRigBetweenPairs) {
  TempDir dir;
  write_capture(dir.path / "c.raw", 20);
  daemon::Settings settings;
  settings.processor.detect =
      false;  // the hand-over and publication are under test, on frames without a board
  const auto pipeline = replay_pipeline(settings, dir.path / "c.raw", "speed=realtime&loop=1");
  pipeline->start();
  auto other = std::make_shared<recon::StereoRig>(*paper_rig());
  other->T *= 2.0;
  const double baseline = other->baseline_mm();
  pipeline->reload_rig(other);
  EXPECT_DOUBLE_EQ(pipeline->rig()->baseline_mm(), baseline);
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (pipeline->status().calibration_reloads == 0 && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_EQ(pipeline->status().calibration_reloads, 1u);
  pipeline->stop();
}

// [recon] mode both on a textured scene: readers always find a result's scene beside it and, when
// the result has a dense map, that map tagged with the result's own sequence number and pair
// (never another pair's map), while the worker publishes and recycles the slots.
TEST(Pipeline, SceneResultsAndTheirMapsBelongToTheirPair) {
  TempDir dir;
  const int n = 3;
  write_scene_capture(dir.path / "s.raw", n);
  daemon::Settings settings;
  settings.processor.mode = app::ReconMode::both;
  const auto pipeline = replay_pipeline(settings, dir.path / "s.raw", "speed=max");
  std::atomic<int> bad{0}, with_scene{0}, with_map{0};
  auto reader = [&](const std::atomic<bool>& done) {
    while (!done.load()) {
      pipeline->results().read_latest([&](const daemon::Published& p, std::uint64_t seq) {
        bad += !p.scene.computed || p.result.pair + 1 != seq;
        with_scene += p.scene.computed && p.scene.sparse.valid_count > 0;
        if (!p.scene.dense) return;
        pipeline->depth_maps().read_seq(seq, [&](const daemon::DepthSlot& d) {
          bad += d.seq != seq || d.pair != p.result.pair || d.map.valid_count != p.scene.depth.valid_count;
          ++with_map;
        });
      });
    }
  };
  process_while_reading(*pipeline, n, std::chrono::seconds(60), reader);
  ASSERT_EQ(pipeline->pairs_processed(), static_cast<std::uint64_t>(n));
  EXPECT_EQ(bad.load(), 0);
  EXPECT_GT(with_scene.load(), 0);
  const auto st = pipeline->status();
  ASSERT_TRUE(st.scene.has_value());
  EXPECT_EQ(st.scene_pairs, static_cast<std::uint64_t>(n));
  EXPECT_GT(st.scene->valid_points, 300);
  // Every pair's map was computed (mode both), and the latest one is summarized in the status.
  EXPECT_EQ(st.dense_pairs, static_cast<std::uint64_t>(n));
  EXPECT_TRUE(st.scene->depth.has_value());
  EXPECT_GT(with_map.load(), 0);
  pipeline->stop();
}
