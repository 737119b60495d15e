// One pair's corners -> PairResult: exact on exact data, measured sigma on noisy data, flags instead
// of numbers for corners a camera cannot use.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/recon/geometry/calibration_uncertainty.hpp"
#include "naneye/recon/pair/reconstruction.hpp"

using namespace naneye::recon;

namespace {

StereoRig rig_d3() {
  return load_rig(std::string(NANEYE_SOURCE_DIR) + "/config/calib/paper-d3.yaml");
}

const BoardGeometry kBoard;  // the paper's board

struct Board {
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  Eigen::Vector3d at(const BoardGeometry& b, int r, int c) const { return R * b.corner(r, c) + t; }
};

Board board_at(double tilt_deg, double z, const BoardGeometry& b, Eigen::Vector2d offset = {0, 0}) {
  Board s;
  s.R = Eigen::AngleAxisd(tilt_deg * M_PI / 180, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  const Eigen::Vector3d centre = b.centre();
  s.t = Eigen::Vector3d(offset.x(), offset.y(), z) - s.R * centre;
  return s;
}

bool inside_fold(const CameraModel& cam, const Eigen::Vector3d& X) {
  const auto r = cam.fold_radius_undistorted();
  return !r || (X.head<2>() / X.z()).norm() < *r;
}

std::vector<CornerObservation> observe(const StereoRig& rig, const BoardGeometry& b, const Board& s,
                                       double noise, std::mt19937& rng) {
  std::normal_distribution<double> n(0, noise);
  std::vector<CornerObservation> obs;
  for (int r = 0; r < b.rows; ++r)
    for (int c = 0; c < b.cols; ++c) {
      CornerObservation o;
      o.row = r;
      o.col = c;
      const Eigen::Vector3d X = s.at(b, r, c);
      o.left_px = rig.left.project(X) + Eigen::Vector2d(n(rng), n(rng));
      o.right_px = rig.right.project(rig.R * X + rig.T) + Eigen::Vector2d(n(rng), n(rng));
      // A corner whose ray lies beyond a camera's fold is not imaged by that camera as the model
      // describes it (its projection folds back onto another ray's pixel): as the simulator and the
      // detector do, such a corner is not used.
      o.left_ok = inside_fold(rig.left, X) && rig.left.in_domain(o.left_px);
      o.right_ok = inside_fold(rig.right, rig.R * X + rig.T) && rig.right.in_domain(o.right_px);
      obs.push_back(o);
    }
  return obs;
}

}  // namespace

TEST(PairReconstruction, ExactDataGivesExactPointsAndZeroCriteria) {
  const StereoRig rig = rig_d3();
  ReconstructionSettings s;
  std::mt19937 rng(1);
  const Board board = board_at(30, 70, kBoard);
  const auto obs = observe(rig, kBoard, board, 0.0, rng);
  PairResult out;
  reconstruct_pair(rig, kBoard, s, obs, out);
  ASSERT_TRUE(out.board_found);
  ASSERT_EQ(out.point_count, 48);
  for (int i = 0; i < 48; ++i) {
    const auto& p = out.points[i];
    ASSERT_TRUE(p.valid) << i;
    const Eigen::Vector3d truth = board.at(kBoard, p.row, p.col);
    EXPECT_LT((p.xyz_mm - truth).norm(), 1e-8) << i;
    EXPECT_LT((p.xyz_board_mm - truth).norm(), 1e-8) << i;
    EXPECT_EQ(p.id, p.row * 8 + p.col);
    // The sigma floor applies (the residuals are zero): Z^2/(f T) sqrt(2) 0.01 px ~ 0.3 mm at 70 mm.
    EXPECT_GT(p.depth_sigma_mm, 0.1);
    EXPECT_LT(p.depth_sigma_mm, 1.0);
    EXPECT_TRUE(std::isnan(p.calib_sigma_mm));  // the paper's file: marginal sigmas, no covariance
  }
  ASSERT_TRUE(out.metrics);
  EXPECT_LT(out.metrics->planarity_mm, 1e-8);
  EXPECT_LT(out.metrics->distance_error_mm, 1e-8);
  EXPECT_LT(out.metrics->reprojection_px, 1e-8);
  EXPECT_NEAR(out.board->distance_mm, std::abs(board.R.col(2).dot(board.t)), 1e-8);
  EXPECT_LT(out.board->rms_px, 1e-8);
}

// With a covariance in the calibration, every valid corner also carries the depth sigma it allows
// there; the points themselves do not change.
TEST(PairReconstruction, CornersCarryTheCalibrationSigmaWhenTheCalibrationHasACovariance) {
  StereoRig rig = rig_d3();
  rig.sigmas.covariance = CalibrationUncertainty::assuming_independent_sigmas(rig)->covariance();
  const auto u = CalibrationUncertainty::of(rig);
  ASSERT_TRUE(u.has_value());
  std::mt19937 rng(3);
  const auto obs = observe(rig, kBoard, board_at(20, 40, kBoard), 0.05, rng);
  PairResult with, without;
  reconstruct_pair(rig, kBoard, {}, obs, with);
  reconstruct_pair(rig_d3(), kBoard, {}, obs, without);
  ASSERT_EQ(with.point_count, without.point_count);
  int valid = 0;
  for (int i = 0; i < with.point_count; ++i) {
    const auto &a = with.points[i], &b = without.points[i];
    ASSERT_EQ(a.valid, b.valid);
    if (!a.valid) {
      EXPECT_TRUE(std::isnan(a.calib_sigma_mm));
      continue;
    }
    ++valid;
    EXPECT_EQ(a.xyz_mm, b.xyz_mm);
    EXPECT_EQ(a.depth_sigma_mm, b.depth_sigma_mm);
    EXPECT_EQ(a.calib_sigma_mm, u->depth_sigma_mm(a.xyz_mm));
  }
  EXPECT_EQ(valid, 48);
}

TEST(PairReconstruction, SigmaIsMeasuredFromThePairsResiduals) {
  const StereoRig rig = rig_d3();
  ReconstructionSettings s;
  std::mt19937 rng(2);
  double sum = 0;
  const int trials = 50;
  for (int k = 0; k < trials; ++k) {
    const auto obs = observe(rig, kBoard, board_at(20, 70, kBoard), 0.2, rng);
    PairResult out;
    reconstruct_pair(rig, kBoard, s, obs, out);
    ASSERT_TRUE(out.board_found);
    const BoardPose pose = estimate_board_pose(rig, kBoard, obs, 1.0);
    sum += measured_corner_sigma(pose, s) / trials;
  }
  EXPECT_NEAR(sum, 0.2, 0.02);
}

// Depth sigma of a triangulated corner agrees with its spread over noisy trials.
TEST(PairReconstruction, TriangulatedDepthSigmaIsHonest) {
  const StereoRig rig = rig_d3();
  ReconstructionSettings s;
  std::mt19937 rng(5);
  const Board board = board_at(10, 70, kBoard);
  const int trials = 300;
  std::vector<double> err;
  double mean_sigma = 0;
  for (int k = 0; k < trials; ++k) {
    PairResult out;
    reconstruct_pair(rig, kBoard, s, observe(rig, kBoard, board, 0.1, rng), out);
    const auto& p = out.points[20];
    ASSERT_TRUE(p.valid);
    err.push_back(p.xyz_mm.z() - board.at(kBoard, p.row, p.col).z());
    mean_sigma += p.depth_sigma_mm / trials;
  }
  double var = 0;
  for (double e : err) var += e * e / trials;
  EXPECT_NEAR(mean_sigma, std::sqrt(var), 0.15 * std::sqrt(var));
}

TEST(PairReconstruction, CornersBeyondTheFoldAreFlaggedNotNumbers) {
  const StereoRig rig = rig_d3();
  ReconstructionSettings s;
  std::mt19937 rng(3);
  // A close board, off to the top-left corner: some corners land beyond the left camera's fold.
  const Board board = board_at(0, 30, kBoard, {-14, -14});
  const auto obs = observe(rig, kBoard, board, 0.0, rng);
  int beyond = 0;
  for (const auto& o : obs) beyond += !o.left_ok;
  ASSERT_GT(beyond, 0);
  ASSERT_LT(beyond, 40);
  PairResult out;
  reconstruct_pair(rig, kBoard, s, obs, out);
  ASSERT_TRUE(out.board_found);
  int invalid = 0;
  for (int i = 0; i < out.point_count; ++i) {
    const auto& o = obs[i];
    const auto& p = out.points[i];
    EXPECT_EQ(p.valid, o.left_ok && o.right_ok) << i;
    invalid += !p.valid;
    if (p.valid) {
      EXPECT_LT((p.xyz_mm - board.at(kBoard, p.row, p.col)).norm(), 1e-8);
    }
  }
  EXPECT_EQ(invalid, beyond);
  EXPECT_LT(out.metrics->planarity_mm, 1e-8);
}

TEST(PairReconstruction, NoCornersNoBoard) {
  const StereoRig rig = rig_d3();
  PairResult out;
  out.board_found = true;
  reconstruct_pair(rig, kBoard, ReconstructionSettings{}, {}, out);
  EXPECT_FALSE(out.board_found);
  EXPECT_FALSE(out.board);
  EXPECT_FALSE(out.metrics);
  EXPECT_EQ(out.point_count, 0);
}
