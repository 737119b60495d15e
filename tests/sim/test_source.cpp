// sim:// through the registry: pairs arrive through the driver's own path, repeatably.
#include <gtest/gtest.h>

#include "naneye/driver/source_registry.hpp"
#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/sim/sim_source.hpp"

namespace naneye::sim {
namespace {

driver::SourceRegistry registry() {
  driver::SourceRegistry r = driver::make_default_registry();
  register_sim_source(r);
  return r;
}

std::vector<std::unique_ptr<driver::StereoPair>> take(const std::string& uri,
                                                      driver::SourceCounters* c = nullptr,
                                                      driver::SourceState* state = nullptr) {
  auto src = registry().open(uri);
  EXPECT_EQ(src->info().kind, "sim");
  src->start();
  std::vector<std::unique_ptr<driver::StereoPair>> out;
  while (auto p = src->next(std::chrono::milliseconds(10000)))
    out.push_back(std::make_unique<driver::StereoPair>(*p));
  if (c) *c = src->counters();
  if (state) *state = src->state();
  src->stop();
  return out;
}

TEST(SimSource, DeliversPairsThroughTheDriverPath) {
  driver::SourceCounters c;
  driver::SourceState state{};
  const auto pairs = take("sim://paper-d3?pairs=3&speed=max&seed=2&motion=sweep", &c, &state);
  ASSERT_EQ(pairs.size(), 3u);
  EXPECT_EQ(state, driver::SourceState::finished);
  EXPECT_EQ(c.records, 6u);
  EXPECT_EQ(c.pairs, 3u);
  EXPECT_EQ(c.sync_losses + c.seq_gaps + c.cut_records + c.reference_failures + c.unpaired, 0u);
  for (const auto& p : pairs) {
    EXPECT_GT(p->offset_ns(), 0);
    EXPECT_LT(p->offset_ns(), 10'000'000);  // within half a frame period
    EXPECT_EQ(p->left.reference, naneye::driver::ReferenceStatus::passed);
    EXPECT_EQ(p->right.reference, naneye::driver::ReferenceStatus::passed);
  }
  // The same seed renders the same pairs.
  const auto again = take("sim://paper-d3?pairs=1&speed=max&seed=2&motion=sweep");
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0]->left.pixels, pairs[0]->left.pixels);
  EXPECT_EQ(again[0]->right.pixels, pairs[0]->right.pixels);
}

TEST(SimSource, RealtimePacingKeepsTheFrameRate) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto pairs = take("sim://paper-d2?pairs=4&fps=50&noise=0");
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_EQ(pairs.size(), 4u);
  // Three frame periods at 43-62 fps pass between the first and the last pair.
  EXPECT_GE(s, 3.0 / 62.0);
  const double span_ms = 1e-6 * static_cast<double>(pairs[3]->left.sensor_ns - pairs[0]->left.sensor_ns);
  EXPECT_GE(span_ms, 3000.0 / 62.0);
  EXPECT_LE(span_ms, 3000.0 / 43.0);
}

TEST(SimSource, RefusesBadParameters) {
  const auto r = registry();
  EXPECT_THROW(r.open("sim://paper-d9"), driver::SourceError);
  EXPECT_THROW(r.open("sim://paper-d3?fps=100"), driver::SourceError);
  EXPECT_THROW(r.open("sim://paper-d3?motion=spin"), driver::SourceError);
  EXPECT_THROW(r.open("sim://paper-d3?colour=1"), driver::SourceError);
  EXPECT_NO_THROW(r.open("sim://paper-d1?fps=43&motion=still&bayer=1&pairs=2"));
}

TEST(SimSource, TrajectoriesKeepTheWholeBoardInView) {
  for (const auto& preset : presets()) {
    const recon::StereoRig rig = recon::load_rig(find_calibration(preset.calib_file));
    BoardGeometry board;
    board.square_mm = preset.square_mm;
    PoseSettings ps;
    ps.margin_px = 2;
    for (Motion m : {Motion::orbit, Motion::sweep, Motion::still})
      for (double t = 0; t < 12.0; t += 0.25)
        EXPECT_TRUE(pose_fully_visible(rig, board, trajectory_pose(m, board, preset.distance_mm, t), ps))
            << preset.name << " motion " << static_cast<int>(m) << " t " << t;
  }
}

}  // namespace
}  // namespace naneye::sim
