// Board pose from both eyes: exact on exact data, honest sigma on noisy data.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/recon/geometry/board_pose.hpp"

using namespace naneye::recon;

namespace {

StereoRig rig_d3() {
  return load_rig(std::string(NANEYE_SOURCE_DIR) + "/config/calib/paper-d3.yaml");
}

struct Scene {
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
};

// A board ~70 mm away, tilted, centred on the optical axis.
Scene scene(double tilt_x_deg, double tilt_y_deg, double z_mm, const BoardGeometry& b) {
  Scene s;
  s.R = (Eigen::AngleAxisd(tilt_y_deg * M_PI / 180, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(tilt_x_deg * M_PI / 180, Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
  const Eigen::Vector3d centre((b.cols - 1) * b.square_mm / 2, (b.rows - 1) * b.square_mm / 2, 0);
  s.t = Eigen::Vector3d(0, 0, z_mm) - s.R * centre;
  return s;
}

std::vector<CornerObservation> observe(const StereoRig& rig, const BoardGeometry& b, const Scene& s,
                                       double noise_px = 0, std::mt19937* rng = nullptr) {
  std::normal_distribution<double> n(0, noise_px);
  std::vector<CornerObservation> obs;
  for (int r = 0; r < b.rows; ++r) {
    for (int c = 0; c < b.cols; ++c) {
      const Eigen::Vector3d X = s.R * b.corner(r, c) + s.t;
      CornerObservation o;
      o.row = r;
      o.col = c;
      o.left_px = rig.left.project(X);
      o.right_px = rig.right.project(rig.R * X + rig.T);
      if (rng) {
        o.left_px += Eigen::Vector2d(n(*rng), n(*rng));
        o.right_px += Eigen::Vector2d(n(*rng), n(*rng));
      }
      o.left_ok = rig.left.in_domain(o.left_px);
      o.right_ok = rig.right.in_domain(o.right_px);
      obs.push_back(o);
    }
  }
  return obs;
}

}  // namespace

TEST(BoardPose, ExactOnExactData) {
  const StereoRig rig = rig_d3();
  const BoardGeometry b;
  for (const auto& [tx, ty, z] : {std::tuple{0.0, 0.0, 70.0}, {25.0, -30.0, 60.0}, {-35.0, 15.0, 85.0}}) {
    const Scene s = scene(tx, ty, z, b);
    const auto obs = observe(rig, b, s);
    const BoardPose p = estimate_board_pose(rig, b, obs, 0.05);
    ASSERT_TRUE(p.ok);
    EXPECT_LT((p.t - s.t).norm(), 1e-9) << tx << " " << ty;
    EXPECT_LT((p.R - s.R).norm(), 1e-11);
    EXPECT_LT(p.rms_px, 1e-9);
    EXPECT_EQ(p.residuals, 4 * b.rows * b.cols);
    // The plane's normal faces the camera, its distance is n . t.
    EXPECT_LT(p.normal().dot(p.t), 0.0);
    EXPECT_NEAR(p.plane_distance_mm(), std::abs(s.R.col(2).dot(s.t)), 1e-9);
  }
}

TEST(BoardPose, RightEyeAloneInitialises) {
  const StereoRig rig = rig_d3();
  const BoardGeometry b;
  const Scene s = scene(10, 20, 70, b);
  auto obs = observe(rig, b, s);
  for (auto& o : obs) o.left_ok = false;
  const BoardPose p = estimate_board_pose(rig, b, obs, 0.05);
  ASSERT_TRUE(p.ok);
  EXPECT_LT((p.t - s.t).norm(), 1e-9);
}

TEST(BoardPose, TooFewCornersRefused) {
  const StereoRig rig = rig_d3();
  const BoardGeometry b;
  auto obs = observe(rig, b, scene(0, 0, 70, b));
  obs.resize(2);
  EXPECT_FALSE(estimate_board_pose(rig, b, obs, 0.05).ok);
}

// The propagated sigma of the depth at the image centre matches the Monte-Carlo spread, and is far
// below what a 1 mm baseline gives one triangulated corner (paper Eq. 2: Z^2 / (f T) sigma_d).
TEST(BoardPose, DepthSigmaMatchesMonteCarlo) {
  const StereoRig rig = rig_d3();
  const BoardGeometry b;
  const Scene s = scene(20, -15, 70, b);
  const double sigma = 0.1;
  std::mt19937 rng(3);
  const Eigen::Vector2d centre_px = rig.left.project(s.R * b.corner(3, 4) + s.t);
  std::vector<double> depths;
  double predicted = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const auto obs = observe(rig, b, s, sigma, &rng);
    const BoardPose p = estimate_board_pose(rig, b, obs, sigma);
    ASSERT_TRUE(p.ok);
    const auto hit = intersect_board(rig, p, centre_px);
    ASSERT_TRUE(hit);
    depths.push_back(hit->depth_mm);
    predicted += hit->depth_sigma_mm / 400;
  }
  double mean = 0, var = 0;
  for (double d : depths) mean += d / depths.size();
  for (double d : depths) var += (d - mean) * (d - mean) / (depths.size() - 1);
  const double spread = std::sqrt(var);
  const double truth = (s.R * b.corner(3, 4) + s.t).z();
  EXPECT_NEAR(mean, truth, 4 * spread / std::sqrt(400.0) + 1e-3);
  EXPECT_NEAR(predicted, spread, 0.15 * spread);
  // Per-corner stereo at this distance: sqrt(2) * sigma disparity over f T / Z^2 mm per px.
  const double per_corner = 70.0 * 70.0 / (216.3 * rig.baseline_mm()) * std::sqrt(2.0) * sigma;
  EXPECT_LT(spread, per_corner / 10);
}

TEST(BoardPose, RayOutsideDomainOrBehindRefused) {
  const StereoRig rig = rig_d3();
  const BoardGeometry b;
  const Scene s = scene(0, 0, 70, b);
  const BoardPose p = estimate_board_pose(rig, b, observe(rig, b, s), 0.05);
  ASSERT_TRUE(p.ok);
  EXPECT_FALSE(intersect_board(rig, p, Eigen::Vector2d(0, 0)));  // beyond the left camera's fold
  const auto hit = intersect_board(rig, p, Eigen::Vector2d(rig.left.cx(), rig.left.cy()));
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->depth_mm, 70.0, 1e-9);
}
