// `naneye calibrate --left ... --right ...` on real photographs nobody here rendered: OpenCV's sample
// stereo set (Debian's opencv-doc, 13 pairs of a 9 x 6 inner-corner board of 25 mm squares, a lens
// nobody gave us). Its left fx must be within 1 % of OpenCV's own calibration of the same images
// (calibrateCamera on findChessboardCorners + cornerSubPix, made here), its RMS below the 0.39 px of
// the set's left_intrinsics.yml, every free parameter with a sigma.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "run_cli.hpp"

namespace {

const std::string kDir = "/usr/share/doc/opencv-doc/examples/data";

// OpenCV's calibration of one eye, as a user of OpenCV would make it (default flags).
double opencv_fx(const char* side, double& rms) {
  std::vector<std::vector<cv::Point2f>> image;
  std::vector<std::vector<cv::Point3f>> object;
  for (int k = 1; k <= 14; ++k) {
    char name[128];
    std::snprintf(name, sizeof name, "%s/%s%02d.jpg", kDir.c_str(), side, k);
    const cv::Mat g = cv::imread(name, cv::IMREAD_GRAYSCALE);
    if (g.empty()) continue;  // the set has no pair 10
    std::vector<cv::Point2f> p;
    if (!cv::findChessboardCorners(g, cv::Size(9, 6), p,
                                   cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE))
      continue;
    cv::cornerSubPix(g, p, cv::Size(11, 11), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 30, 0.01));
    image.push_back(p);
    auto& o = object.emplace_back();
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 9; ++c)
        o.emplace_back(25.0f * static_cast<float>(c), 25.0f * static_cast<float>(r), 0.0f);
  }
  cv::Mat K, D;
  std::vector<cv::Mat> rv, tv;
  rms = cv::calibrateCamera(object, image, cv::Size(640, 480), K, D, rv, tv);
  return K.at<double>(0, 0);
}

TEST(CalibratePhotographs, OpenCvSampleSetLeftFxWithinOnePercentOfOpenCvs) {
  if (!std::filesystem::exists(kDir + "/left01.jpg"))
    GTEST_SKIP() << "opencv-doc is not installed (scripts/install-deps.sh installs it)";
  const std::string out = (std::filesystem::temp_directory_path() / "naneye-photo-calib.yaml").string();
  const auto r = naneye::test::run_cli("calibrate --left '" + kDir + "/left[0-9]*.jpg' --right '" + kDir +
                                       "/right[0-9]*.jpg' --pattern 6x9 --square-mm 25 --json -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  double fx = 0;
  for (const auto& p : j["parameters"]) {
    if (p["name"] == "left.fx") fx = p["value"].get<double>();
    if (!p["fixed"].get<bool>()) {
      EXPECT_GT(p["sigma"].get<double>(), 0.0) << p["name"];
    }
  }
  double cv_rms = 0;
  const double cv_fx = opencv_fx("left", cv_rms);
  const double rms = j["rms_px"].get<double>();
  std::printf(
      "naneye calibrate: left fx %.2f px, RMS %.4f px, %d pairs; OpenCV calibrateCamera (left): fx %.2f px, "
      "RMS %.4f px\n",
      fx, rms, j["pairs"].get<int>(), cv_fx, cv_rms);
  EXPECT_EQ(j["pairs"].get<int>(), 13);
  EXPECT_LE(std::abs(fx - cv_fx), 0.01 * cv_fx);
  EXPECT_LT(rms, 0.39);
  // The file carries the calibration's covariance, so `calib info` gives the depth sigma it allows,
  // growing with depth (at 10 baselines ~0.08 %, docs/scene.md "Calibration uncertainty").
  const auto info = naneye::test::run_cli("calib info --json " + out);
  ASSERT_EQ(info.exit_code, 0) << info.out;
  const auto ji = nlohmann::json::parse(info.out);
  const auto& on_axis = ji["calibration_depth_sigma"]["on_axis"];
  ASSERT_GE(on_axis.size(), 2u) << info.out;
  for (std::size_t i = 0; i < on_axis.size(); ++i) {
    const double rel = on_axis[i]["sigma_mm"].get<double>() / on_axis[i]["z_mm"].get<double>();
    EXPECT_GT(rel, 1e-4);
    EXPECT_LT(rel, 0.05);
    if (i) {
      EXPECT_GT(on_axis[i]["sigma_mm"].get<double>(), on_axis[i - 1]["sigma_mm"].get<double>());
    }
  }
  std::filesystem::remove(out);
}

// On real photographs the halves' depths differ by more than honest sigmas allow by chance
// (kHonestDepthRatioRmsMax): `--cross-validate` writes the measured factor as
// calibration_sigma_scale, and `calib info` widens every calibration sigma by it; the same
// calibration without the cross-validation is left as the bundle made it.
TEST(CalibratePhotographs, CrossValidationWidensTheUnderstatedSigmas) {
  if (!std::filesystem::exists(kDir + "/left01.jpg"))
    GTEST_SKIP() << "opencv-doc is not installed (scripts/install-deps.sh installs it)";
  const auto tmp = std::filesystem::temp_directory_path();
  const std::string plain = (tmp / "naneye-photo-plain.yaml").string(),
                    checked = (tmp / "naneye-photo-checked.yaml").string();
  const std::string args = "calibrate --left '" + kDir + "/left[0-9]*.jpg' --right '" + kDir +
                           "/right[0-9]*.jpg' --pattern 6x9 --square-mm 25 --json -o ";
  ASSERT_EQ(naneye::test::run_cli(args + plain).exit_code, 0);
  const auto r = naneye::test::run_cli(args + checked + " --cross-validate");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto depth = nlohmann::json::parse(r.out)["cross_validation"]["odd_even"]["depth"];
  const double ratio = depth["ratio_rms"].get<double>(), pooled = depth["pooled_ratio_rms"].get<double>(),
               scale = depth["sigma_scale"].get<double>();
  std::printf(
      "photographs: odd/even depth ratio RMS %.2f, over the three halvings %s, pooled %.2f; sigma "
      "scale written %.2f\n",
      ratio, depth["split_ratio_rms"].dump().c_str(), pooled, scale);
  EXPECT_GT(ratio, 2.0);  // measured 2.64
  EXPECT_EQ(depth["split_ratio_rms"].size(), 3u);
  EXPECT_EQ(depth["split_ratio_rms"][0].get<double>(), ratio);
  EXPECT_GT(pooled, 1.6);
  EXPECT_EQ(scale, pooled);
  const auto a = nlohmann::json::parse(naneye::test::run_cli("calib info --json " + plain).out);
  const auto b = nlohmann::json::parse(naneye::test::run_cli("calib info --json " + checked).out);
  EXPECT_EQ(a["calibration_depth_sigma"]["scale"].get<double>(), 1.0);
  EXPECT_NEAR(b["calibration_depth_sigma"]["scale"].get<double>(), scale, 1e-9 * scale);
  const auto& pa = a["calibration_depth_sigma"]["on_axis"];
  const auto& pb = b["calibration_depth_sigma"]["on_axis"];
  ASSERT_EQ(pa.size(), pb.size());
  ASSERT_GE(pa.size(), 1u);
  for (std::size_t i = 0; i < pa.size(); ++i)
    EXPECT_NEAR(pb[i]["sigma_mm"].get<double>(), scale * pa[i]["sigma_mm"].get<double>(),
                1e-6 * pb[i]["sigma_mm"].get<double>());
  const auto text = naneye::test::run_cli("calib info " + checked).out;
  EXPECT_NE(text.find("widened"), std::string::npos) << text;
  std::filesystem::remove(plain);
  std::filesystem::remove(checked);
}

}  // namespace
