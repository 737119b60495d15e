// The bundled captures (tests/data/sim-*, made by scripts/make-test-data.sh) still replay as their
// truth.json describes: every pair, at its time, with its board where the camera model puts it.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "naneye/driver/source_registry.hpp"
#include "naneye/recon/camera/calibration_io.hpp"

namespace naneye {
namespace {

namespace fs = std::filesystem;

TEST(Bundled, EveryCaptureReplaysAsItsTruthSays) {
  int captures = 0;
  for (const char* name : {"sim-d3-mono", "sim-d3-bayer", "sim-d1-cut"}) {
    const fs::path dir = fs::path(NANEYE_TEST_DATA_DIR) / name;
    ASSERT_TRUE(fs::exists(dir / "capture.raw")) << dir;
    std::ifstream tf(dir / "truth.json");
    const nlohmann::json truth = nlohmann::json::parse(tf);
    const recon::StereoRig rig = recon::load_rig(fs::path(NANEYE_SOURCE_DIR) / "config/calib" /
                                                 truth["calibration"].get<std::string>());
    const bool bayer = truth["bayer"].get<bool>();
    auto src = driver::make_default_registry().open("file://" + (dir / "capture.raw").string() +
                                                    "?speed=max&color=" + (bayer ? "grbg" : "mono"));
    src->start();
    std::size_t i = 0;
    std::int64_t t0 = 0;
    while (auto p = src->next(std::chrono::milliseconds(5000))) {
      ASSERT_LT(i, truth["pairs"].size());
      const auto& t = truth["pairs"][i];
      if (i == 0) t0 = p->left.sensor_ns;
      EXPECT_NEAR(p->left.sensor_ns - t0, t["t_left_ns"].get<double>(), 1.0) << name << " pair " << i;
      EXPECT_NEAR(p->offset_ns(), t["t_right_ns"].get<double>() - t["t_left_ns"].get<double>(), 2.0);
      EXPECT_EQ(p->left.color, bayer ? driver::ColorMode::bayer_grbg : driver::ColorMode::mono);
      // Where the board is whole, its squares are where the pose puts them: around every inner corner
      // (i, j) the square below-right is black when i + j is even (the renderer's convention), the one
      // below-left white; checked a third of a square into each, in both images.
      if (t["board_in_view"].get<bool>()) {
        Eigen::Matrix3d R;
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) R(r, c) = t["board_rotation"][r][c].get<double>();
        const Eigen::Vector3d T(t["board_translation_mm"][0].get<double>(),
                                t["board_translation_mm"][1].get<double>(),
                                t["board_translation_mm"][2].get<double>());
        const double s = truth["square_mm"].get<double>() / 3;
        int wrong = 0;
        for (int k = 0; k < 48; ++k) {
          const int row = k / 8, col = k % 8;
          const Eigen::Vector3d corner(col * 3 * s, row * 3 * s, 0);
          for (int eye = 0; eye < 2; ++eye) {
            auto value = [&](double du, double dv) {
              Eigen::Vector3d X = R * (corner + Eigen::Vector3d(du, dv, 0)) + T;
              const recon::CameraModel& cam = eye == 0 ? rig.left : rig.right;
              if (eye == 1) X = rig.R * X + rig.T;
              const Eigen::Vector2d px = cam.project(X);
              const driver::Frame& f = eye == 0 ? p->left : p->right;
              return static_cast<int>(
                  f.at(static_cast<int>(std::lround(px.y())), static_cast<int>(std::lround(px.x()))));
            };
            const int below_right = value(s, s), below_left = value(-s, s);
            const bool black_right = (row + col) % 2 == 0;
            wrong += black_right ? !(below_right + 100 < below_left) : !(below_left + 100 < below_right);
          }
        }
        // Defect pixels may sit on a probe point: a few disagreements at most.
        EXPECT_LE(wrong, 2) << name << " pair " << i;
      }
      ++i;
    }
    EXPECT_EQ(i, truth["pairs"].size()) << name;
    const driver::SourceCounters c = src->counters();
    EXPECT_EQ(c.sync_losses + c.seq_gaps + c.cut_records + c.reference_failures + c.unpaired, 0u) << name;
    src->stop();
    ++captures;
  }
  EXPECT_EQ(captures, 3);
}

}  // namespace
}  // namespace naneye
