// sim:// on the textured scenes (issue 14): the presets open through the registry, the frames are
// the textured renderer's through the driver path, and the hand-held camera moves smoothly.
#include <gtest/gtest.h>

#include <cmath>

#include "naneye/driver/source_registry.hpp"
#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/sim/sim_source.hpp"
#include "naneye/sim/textured.hpp"

namespace naneye::sim {
namespace {

driver::SourceUri uri(const std::string& text) {
  return driver::parse_uri(text);
}

TEST(TexturedSimSource, PresetsParseWithTheirOwnDefaults) {
  for (const auto& name : textured_preset_names()) {
    const auto o = parse_sim_uri(uri("sim://" + name));
    EXPECT_TRUE(o.textured) << name;
    EXPECT_EQ(o.motion, Motion::handheld) << name;
    EXPECT_DOUBLE_EQ(o.fps, 10.0) << name;
    EXPECT_EQ(o.supersample, 1) << name;
  }
  const auto board = parse_sim_uri(uri("sim://paper-d3"));
  EXPECT_FALSE(board.textured);
  EXPECT_EQ(board.motion, Motion::orbit);
  EXPECT_EQ(parse_sim_uri(uri("sim://sphere?fps=62&supersample=3&motion=still")).supersample, 3);
  // Refused by name: a board trajectory on a scene, a scene option on a board, rates out of range.
  EXPECT_THROW(parse_sim_uri(uri("sim://sphere?motion=orbit")), driver::SourceError);
  EXPECT_THROW(parse_sim_uri(uri("sim://paper-d3?motion=handheld")), driver::SourceError);
  EXPECT_THROW(parse_sim_uri(uri("sim://paper-d3?supersample=2")), driver::SourceError);
  EXPECT_THROW(parse_sim_uri(uri("sim://tube?fps=0")), driver::SourceError);
  EXPECT_THROW(parse_sim_uri(uri("sim://tube?supersample=4")), driver::SourceError);
  EXPECT_THROW(parse_sim_uri(uri("sim://cube")), driver::SourceError);
}

TEST(TexturedSimSource, DeliversTheRenderersFramesThroughTheDriverPath) {
  driver::SourceRegistry r = driver::make_default_registry();
  register_sim_source(r);
  auto src = r.open("sim://plane?pairs=2&speed=max&seed=3&noise=0&motion=still");
  src->start();
  std::vector<std::unique_ptr<driver::StereoPair>> pairs;
  while (auto p = src->next(std::chrono::milliseconds(20000)))
    pairs.push_back(std::make_unique<driver::StereoPair>(*p));
  const auto c = src->counters();
  src->stop();
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(c.sync_losses + c.seq_gaps + c.cut_records + c.reference_failures + c.unpaired, 0u);
  // Noise-free and still: both pairs equal the renderer's own frames of the preset.
  const recon::StereoRig rig = recon::load_rig(find_calibration("paper-d3.yaml"));
  const TexturedRenderer renderer(rig, SensorSettings::ideal(), 1);
  Rng rng(1);
  cv::Mat left, right;
  renderer.render_frames(*textured_preset("plane"), rng, left, right);
  for (const auto& p : pairs) {
    int differ = 0;
    for (std::size_t i = 0; i < driver::kPixelCount; ++i) {
      differ += p->left.pixels[i] != left.ptr<std::uint16_t>()[i];
      differ += p->right.pixels[i] != right.ptr<std::uint16_t>()[i];
    }
    EXPECT_EQ(differ, 0);
  }
  // A textured surface, not a blank: the left frame's active pixels spread over many values.
  cv::Mat active = left(cv::Rect(60, 60, 130, 130));
  cv::Scalar mean, sd;
  cv::meanStdDev(active, mean, sd);
  EXPECT_GT(sd[0], 20.0);
}

TEST(TexturedSimSource, HandHeldCameraMovesSlowlyAndKeepsTheScenesInRange) {
  // At 62 fps the camera moves well under a pixel's footprint per pair, and the scene stays within
  // the 8-80 mm wherever the motion takes it (checked on the truth of the moved scenes).
  const recon::StereoRig rig = recon::load_rig(find_calibration("paper-d3.yaml"));
  const TexturedRenderer renderer(rig, SensorSettings::ideal(), 1);
  for (const auto& name : textured_preset_names()) {
    const auto scene = *textured_preset(name);
    double max_step = 0, max_turn = 0;
    for (int k = 1; k < 62 * 20; ++k) {
      const Pose a = handheld_camera_pose(scene.light_reference_mm, (k - 1) / 62.0);
      const Pose b = handheld_camera_pose(scene.light_reference_mm, k / 62.0);
      max_step = std::max(max_step, (b.t - a.t).norm());
      max_turn =
          std::max(max_turn, std::acos(std::clamp(((a.R.transpose() * b.R).trace() - 1) / 2, -1.0, 1.0)));
    }
    // A pixel spans ~Z/216 mm: at the preset's scale that is >= 0.046 mm.
    EXPECT_LT(max_step, scene.light_reference_mm / 216.0) << name;
    EXPECT_LT(max_turn, 0.5 / 216.0) << name;  // rad: half a pixel at the image centre
    for (double t : {0.0, 3.1, 7.7}) {
      const Surface s = seen_from(scene, handheld_camera_pose(scene.light_reference_mm, t)).surface;
      double lo = 1e9, hi = 0;
      int n = 0;  // on every 5th pixel of both axes (2 500 rays): the whole truth map takes ~0.2 s
      for (int v = 0; v < 250; v += 5)
        for (int u = 0; u < 250; u += 5)
          if (const auto z = renderer.truth_depth_at(s, Eigen::Vector2d(u, v))) {
            lo = std::min(lo, *z), hi = std::max(hi, *z), ++n;
          }
      EXPECT_GT(n, 800) << name << " t " << t;
      EXPECT_GE(lo, 8.0) << name << " t " << t;
      // The tube is closed at 80 mm (80.3 along a ray off its axis); the hand moves the camera up to
      // 10 % of its 10 mm scale (1 mm) back from it, and turns it by up to 3 deg: 81.8 mm at most.
      EXPECT_LE(hi, 81.8) << name << " t " << t;
    }
  }
}

}  // namespace
}  // namespace naneye::sim
