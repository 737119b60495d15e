// `naneye calib export`: the files load back in the readers users have (yaml-cpp, which ROS reads
// camera_info with; OpenCV FileStorage) and project the same points as the source calibration.
#include <yaml-cpp/yaml.h>

#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <sstream>

#include "run_cli.hpp"

using naneye::test::run_cli;

namespace {

const std::string kCalib = std::string(NANEYE_SOURCE_DIR) + "/config/calib/paper-d3.yaml";

struct Camera {
  cv::Mat K, D;
};

Camera source_camera(bool left) {
  cv::FileStorage fs(kCalib, cv::FileStorage::READ);
  Camera c;
  fs[left ? "M1" : "M2"] >> c.K;
  fs[left ? "D1" : "D2"] >> c.D;
  return c;
}

// 3D points whose normalized image coordinates lie within radius 0.5 (well inside the left camera's
// fold, r_d 0.64): the domain where the model is defined.
std::vector<cv::Point3d> domain_points() {
  std::vector<cv::Point3d> pts;
  for (double x = -0.35; x <= 0.351; x += 0.05)
    for (double y = -0.35; y <= 0.351; y += 0.05) pts.emplace_back(x * 70, y * 70, 70);
  return pts;
}

double max_projection_difference(const Camera& a, const Camera& b) {
  std::vector<cv::Point2d> pa, pb;
  const cv::Mat rvec = cv::Mat::zeros(3, 1, CV_64F), tvec = cv::Mat::zeros(3, 1, CV_64F);
  cv::projectPoints(domain_points(), rvec, tvec, a.K, a.D, pa);
  cv::projectPoints(domain_points(), rvec, tvec, b.K, b.D, pb);
  double worst = 0;
  for (std::size_t i = 0; i < pa.size(); ++i) worst = std::max(worst, cv::norm(pa[i] - pb[i]));
  return worst;
}

std::filesystem::path fresh_dir(const char* name) {
  // Per process: the plain and sanitizer suites may run at once on one machine.
  const auto d =
      std::filesystem::path(::testing::TempDir()) / (std::string(name) + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  return d;
}

}  // namespace

TEST(CalibExport, RosCameraInfoLoadsBackAndProjectsTheSame) {
  const auto dir = fresh_dir("naneye-export-ros");
  const auto r = run_cli("calib export " + kCalib + " --format ros --out " + dir.string(), true);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  for (const bool left : {true, false}) {
    const auto file = dir / (left ? "left.yaml" : "right.yaml");
    const YAML::Node y = YAML::LoadFile(file.string());
    EXPECT_EQ(y["image_width"].as<int>(), 250);
    EXPECT_EQ(y["image_height"].as<int>(), 250);
    EXPECT_EQ(y["distortion_model"].as<std::string>(), "plumb_bob");
    EXPECT_EQ(y["camera_matrix"]["rows"].as<int>(), 3);
    const auto k = y["camera_matrix"]["data"].as<std::vector<double>>();
    const auto d = y["distortion_coefficients"]["data"].as<std::vector<double>>();
    ASSERT_EQ(k.size(), 9u);
    ASSERT_EQ(d.size(), 5u);
    Camera c;
    c.K = cv::Mat(k, true).reshape(1, 3);
    c.D = cv::Mat(d, true).reshape(1, 1);
    EXPECT_LE(max_projection_difference(source_camera(left), c), 1e-9) << file;
    const auto rect = y["rectification_matrix"]["data"].as<std::vector<double>>();
    ASSERT_EQ(rect.size(), 9u);
    ASSERT_EQ(y["projection_matrix"]["data"].as<std::vector<double>>().size(), 12u);
    const cv::Mat R = cv::Mat(rect, true).reshape(1, 3);
    EXPECT_LE(cv::norm(R * R.t() - cv::Mat::eye(3, 3, CV_64F), cv::NORM_INF), 1e-12);
  }
}

TEST(CalibExport, OpenCvStereoYamlMatchesStereoRectifyAndProjectsTheSame) {
  const auto dir = fresh_dir("naneye-export-opencv");
  const auto r = run_cli("calib export " + kCalib + " --format opencv --out " + dir.string(), true);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  cv::FileStorage fs((dir / "stereo.yml").string(), cv::FileStorage::READ);
  ASSERT_TRUE(fs.isOpened());
  Camera l, rr;
  cv::Mat R, T, R1, R2, P1, P2;
  fs["M1"] >> l.K;
  fs["D1"] >> l.D;
  fs["M2"] >> rr.K;
  fs["D2"] >> rr.D;
  fs["R"] >> R;
  fs["T"] >> T;
  fs["R1"] >> R1;
  fs["R2"] >> R2;
  fs["P1"] >> P1;
  fs["P2"] >> P2;
  EXPECT_LE(max_projection_difference(source_camera(true), l), 1e-9);
  EXPECT_LE(max_projection_difference(source_camera(false), rr), 1e-9);
  // The rotations are Bouguet's, as OpenCV computes them (given no distortion, so that nothing is
  // undistorted beyond the fold to choose the focal length).
  cv::Mat r1, r2, p1, p2, q;
  cv::stereoRectify(l.K, cv::noArray(), rr.K, cv::noArray(), cv::Size(250, 250), R, T, r1, r2, p1, p2, q,
                    cv::CALIB_ZERO_DISPARITY);
  EXPECT_LE(cv::norm(R1, r1, cv::NORM_INF), 1e-12);
  EXPECT_LE(cv::norm(R2, r2, cv::NORM_INF), 1e-12);
  // A point seen by both rectified cameras lies on the same row.
  const cv::Mat X = (cv::Mat_<double>(4, 1) << 3.0, -2.0, 60.0, 1.0);
  cv::Mat Xr = cv::Mat::eye(4, 4, CV_64F);
  R.copyTo(Xr(cv::Rect(0, 0, 3, 3)));
  T.copyTo(Xr(cv::Rect(3, 0, 1, 3)));
  cv::Mat rect1 = cv::Mat::eye(4, 4, CV_64F), rect2 = cv::Mat::eye(4, 4, CV_64F);
  R1.copyTo(rect1(cv::Rect(0, 0, 3, 3)));
  R2.copyTo(rect2(cv::Rect(0, 0, 3, 3)));
  const cv::Mat a = P1 * rect1 * X, b = P2 * rect2 * Xr * X;
  EXPECT_NEAR(a.at<double>(1) / a.at<double>(2), b.at<double>(1) / b.at<double>(2), 1e-9);
  EXPECT_GT(a.at<double>(0) / a.at<double>(2) - b.at<double>(0) / b.at<double>(2), 0);  // positive disparity
}

TEST(CalibExport, MrcalModelsHoldTheExactIntrinsics) {
  const auto dir = fresh_dir("naneye-export-mrcal");
  const auto r = run_cli("calib export " + kCalib + " --format mrcal --out " + dir.string(), true);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  std::ifstream in(dir / "left.cameramodel");
  std::stringstream text;
  text << in.rdbuf();
  // No std::regex: under ASan, GCC 12 warns (maybe-uninitialized, an error here) inside <regex>.
  const std::string s = text.str();
  const std::string key = "'intrinsics': [";
  const auto at = s.find(key);
  ASSERT_NE(at, std::string::npos) << s;
  const auto end = s.find(']', at);
  ASSERT_NE(end, std::string::npos) << s;
  std::vector<double> v;
  std::stringstream list(s.substr(at + key.size(), end - at - key.size()));
  for (std::string item; std::getline(list, item, ',');) v.push_back(std::stod(item));
  ASSERT_EQ(v.size(), 9u);
  const Camera src = source_camera(true);
  const Camera back{(cv::Mat_<double>(3, 3) << v[0], 0, v[2], 0, v[1], v[3], 0, 0, 1),
                    (cv::Mat_<double>(1, 5) << v[4], v[5], v[6], v[7], v[8])};
  EXPECT_LE(max_projection_difference(src, back), 1e-9);
  EXPECT_NE(s.find("LENSMODEL_OPENCV5"), std::string::npos);
}

TEST(CalibExport, UnknownFormatIsRefusedAndWritesNothing) {
  const auto dir = fresh_dir("naneye-export-bad");
  const auto r = run_cli("calib export " + kCalib + " --format kalibr --out " + dir.string(), true);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.out.find("kalibr"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir));
}
