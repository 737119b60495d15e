// `naneye recon --scene` run as a user runs it, on a capture of textured scenes, against the truth.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <vector>

#include "../support/correlated_covariance.hpp"
#include "../tools/run_cli.hpp"
#include "naneye/recon/camera/calibration_io.hpp"
#include "scene_fixture.hpp"

namespace naneye {
namespace {

TEST(ReconSceneCli, SceneObjectPerPairAgreesWithTruth) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("naneye-scene-cli-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto raw = dir / "capture.raw";
  const std::vector<sim::TexturedSceneSettings> scenes = {*sim::textured_preset("plane"),
                                                          *sim::textured_preset("sphere")};
  const std::vector<cv::Mat> truth =
      sim::write_textured_capture(raw, test::textured_renderer(false), scenes, 3);
  const std::string calib = std::string(NANEYE_SOURCE_DIR) + "/config/calib/paper-d3.yaml";
  const test::CliResult r = test::run_cli("recon --calib " + calib + " --input " + raw.string() +
                                          " --json --scene --depth-out " + (dir / "depth").string());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  std::istringstream lines(r.out);
  std::string line;
  std::size_t pair = 0;
  bool summary = false;
  while (std::getline(lines, line)) {
    const auto j = nlohmann::json::parse(line);
    if (j.contains("summary")) {  // the last line: pairs per board-failure reason (textured: no board)
      EXPECT_EQ(j["summary"]["pairs"].get<std::size_t>(), truth.size());
      summary = true;
      continue;
    }
    ASSERT_FALSE(summary) << "a pair after the summary line";
    ASSERT_LT(pair, truth.size());
    EXPECT_EQ(j.at("pair").get<std::size_t>(), pair);
    EXPECT_TRUE(j.contains("t_left_ns"));
    const auto& s = j.at("scene");
    // The dense map: its figures in the JSON, its PNGs (0.01 mm per unit, 0 = none) against the truth.
    const auto& d = s.at("depth");
    ASSERT_TRUE(d.is_object());
    char name[32];
    std::snprintf(name, sizeof name, "depth-%06zu.png", pair);
    const cv::Mat z16 = cv::imread((dir / "depth" / name).string(), cv::IMREAD_UNCHANGED);
    std::snprintf(name, sizeof name, "sigma-%06zu.png", pair);
    const cv::Mat s16 = cv::imread((dir / "depth" / name).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(z16.type(), CV_16UC1);
    ASSERT_EQ(s16.type(), CV_16UC1);
    int given = 0, unseen = 0, bad = 0, no_sigma = 0;
    std::vector<double> zs;
    for (int v = 0; v < z16.rows; ++v)
      for (int u = 0; u < z16.cols; ++u) {
        if (z16.at<std::uint16_t>(v, u) == 0) {
          EXPECT_EQ(s16.at<std::uint16_t>(v, u), 0);
          continue;
        }
        ++given;
        const double z = z16.at<std::uint16_t>(v, u) / 100.0, zt = truth[pair].at<double>(v, u);
        zs.push_back(z);
        no_sigma += s16.at<std::uint16_t>(v, u) == 0;
        if (std::isnan(zt)) {
          ++unseen;
          continue;
        }
        bad += std::abs(z - zt) > 0.05 * zt;
      }
    EXPECT_EQ(d.at("valid_pixels").get<int>(), given);
    EXPECT_GE(d.at("valid_share").get<double>(), 0.5);
    EXPECT_EQ(no_sigma, 0);
    EXPECT_LE(unseen, 0.01 * given);
    EXPECT_LE(bad, 0.01 * given);
    std::nth_element(zs.begin(), zs.begin() + static_cast<long>(zs.size() / 2), zs.end());
    EXPECT_NEAR(d.at("median_mm").get<double>(), zs[zs.size() / 2], 0.011);  // the PNG's 0.01 mm rounding
    // The paper's file has no covariance: no calibration sigma, and no PNG of it.
    EXPECT_TRUE(d.at("calib_sigma_median_mm").is_null());
    std::snprintf(name, sizeof name, "calib-sigma-%06zu.png", pair);
    EXPECT_FALSE(std::filesystem::exists(dir / "depth" / name));
    int valid = 0, off = 0;
    for (const auto& p : s.at("points")) {
      if (!p.at("valid").get<bool>()) {
        EXPECT_TRUE(p.at("xyz_mm").is_null());
        EXPECT_TRUE(p.at("depth_sigma_mm").is_null());
        continue;
      }
      ++valid;
      const int u = p.at("left_px")[0].get<int>(), v = p.at("left_px")[1].get<int>();
      const double z = p.at("xyz_mm")[2].get<double>(), zt = truth[pair].at<double>(v, u);
      ASSERT_FALSE(std::isnan(zt)) << "a point where the right eye cannot see the surface";
      EXPECT_GT(p.at("depth_sigma_mm").get<double>(), 0.0);
      off += std::abs(z - zt) > 0.05 * zt;
    }
    EXPECT_EQ(s.at("valid_points").get<int>(), valid);
    EXPECT_GE(valid, 300) << "pair " << pair;
    EXPECT_LE(off, 0.01 * valid) << "pair " << pair;
    ++pair;
  }
  EXPECT_EQ(pair, truth.size());
  EXPECT_TRUE(summary);
  std::filesystem::remove_all(dir);
}

// With a calibration that carries its covariance, a third PNG per pair: the depth sigma the
// calibration allows, given exactly where a depth is, its median in the JSON.
TEST(ReconSceneCli, CalibrationSigmaMapWhenTheFileHasACovariance) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("naneye-scene-cli-cov-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  recon::StereoRig rig = test::paper_d3();
  rig.sigmas.covariance = test::correlated_covariance(rig, 0.1, 5);
  const auto calib = dir / "with-covariance.yaml";
  recon::save_rig(rig, calib);
  const auto raw = dir / "capture.raw";
  sim::write_textured_capture(raw, test::textured_renderer(false), {*sim::textured_preset("sphere")}, 3);
  const test::CliResult r = test::run_cli("recon --calib " + calib.string() + " --input " + raw.string() +
                                          " --json --depth-out " + (dir / "depth").string());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out.substr(0, r.out.find('\n')));
  const auto& d = j.at("scene").at("depth");
  const cv::Mat z16 = cv::imread((dir / "depth" / "depth-000000.png").string(), cv::IMREAD_UNCHANGED);
  const cv::Mat c16 = cv::imread((dir / "depth" / "calib-sigma-000000.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(c16.type(), CV_16UC1);
  ASSERT_EQ(c16.size(), z16.size());
  std::vector<double> sigmas;
  int mismatched = 0;
  for (int v = 0; v < z16.rows; ++v)
    for (int u = 0; u < z16.cols; ++u) {
      mismatched += (z16.at<std::uint16_t>(v, u) == 0) != (c16.at<std::uint16_t>(v, u) == 0);
      if (c16.at<std::uint16_t>(v, u)) sigmas.push_back(c16.at<std::uint16_t>(v, u) / 100.0);
    }
  EXPECT_EQ(mismatched, 0);
  ASSERT_EQ(static_cast<int>(sigmas.size()), d.at("valid_pixels").get<int>());
  std::nth_element(sigmas.begin(), sigmas.begin() + static_cast<long>(sigmas.size() / 2), sigmas.end());
  ASSERT_TRUE(d.at("calib_sigma_median_mm").is_number());
  EXPECT_NEAR(d.at("calib_sigma_median_mm").get<double>(), sigmas[sigmas.size() / 2],
              0.0051);  // 0.01 mm units
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace naneye
