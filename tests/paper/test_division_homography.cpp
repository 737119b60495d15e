// lambda, lambda' and H from plane homographies (Kukelova et al. 2015; paper Eq. 8-9).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "division_scene.hpp"
#include "naneye/recon/paper/division_homography.hpp"

using namespace naneye::recon;
using namespace division_test;

namespace {

struct Truth {
  DivisionEye left, right;
};

// Both variants of the paper with lambdas of the size a NanEye needs (~k1 of the polynomial fit).
Truth pixel_truth(const StereoRig& rig) {
  return {eye(rig.left, DivisionModel::image_centred(-7.9e-6)),
          eye(rig.right, DivisionModel::image_centred(-7.2e-6))};
}
Truth normalized_truth(const StereoRig& rig) {
  return {eye(rig.left, DivisionModel::normalized(-0.37, rig.left.K())),
          eye(rig.right, DivisionModel::normalized(-0.34, rig.right.K()))};
}

PlaneCorrespondences render(const StereoRig& rig, const Truth& t, const BoardGeometry& b,
                            const BoardPlacement& s, double noise_px = 0, std::mt19937* rng = nullptr) {
  std::normal_distribution<double> n(0, noise_px);
  PlaneCorrespondences pc;
  for (int r = 0; r < b.rows; ++r) {
    for (int c = 0; c < b.cols; ++c) {
      const Eigen::Vector3d X = s.R * b.corner(r, c) + s.t;
      Eigen::Vector2d pl = t.left.project_px(X), pr = t.right.project_px(rig.R * X + rig.T);
      if (rng) {
        pl += Eigen::Vector2d(n(*rng), n(*rng));
        pr += Eigen::Vector2d(n(*rng), n(*rng));
      }
      pc.left.push_back(t.left.model.to_model(pl));
      pc.right.push_back(t.right.model.to_model(pr));
    }
  }
  return pc;
}

// The true homography between lifted model coordinates: A_r^-1 K_r (R + T n^T / d) K_l^-1 A_l.
Eigen::Matrix3d true_h(const StereoRig& rig, const Truth& t, const BoardPlacement& s) {
  const Eigen::Matrix3d H =
      t.right.model.A.inverse() * t.right.K * plane_homography(rig, s) * t.left.K.inverse() * t.left.model.A;
  return H / H.norm();
}

double h_error(const Eigen::Matrix3d& est, const Eigen::Matrix3d& truth) {
  return std::min((est - truth).norm(), (est + truth).norm());
}

}  // namespace

TEST(DivisionHomography, ExactOnNoiseFreeDataBothVariants) {
  const StereoRig rig = rig_d3();
  const BoardGeometry b;
  for (const bool pixel : {true, false}) {
    const Truth t = pixel ? pixel_truth(rig) : normalized_truth(rig);
    for (const auto& s : {place_board(0, 0, 70), place_board(25, -30, 60), place_board(-35, 15, 85, 5, -3)}) {
      const PlaneCorrespondences pc = render(rig, t, b, s);
      for (const bool refine : {false, true}) {
        const DivisionHomography h = estimate_division_homography(pc.left, pc.right, {refine});
        ASSERT_TRUE(h.ok);
        EXPECT_NEAR(h.lambda_left, t.left.model.lambda, 1e-9 * std::abs(t.left.model.lambda)) << pixel;
        EXPECT_NEAR(h.lambda_right, t.right.model.lambda, 1e-9 * std::abs(t.right.model.lambda)) << pixel;
        EXPECT_LT(h_error(h.H, true_h(rig, t, s)), 1e-10) << pixel;
        EXPECT_LT(h.linear_rms, 1e-9 * (pixel ? 100.0 : 0.5));
      }
    }
  }
}

TEST(DivisionHomography, SeveralPlanesShareLambdas) {
  const StereoRig rig = rig_d3();
  const BoardGeometry b;
  const Truth t = pixel_truth(rig);
  std::vector<PlaneCorrespondences> planes;
  const auto boards = dataset3_boards(b);
  for (const auto& s : boards) planes.push_back(render(rig, t, b, s));
  const DivisionLambdas est = estimate_division_lambdas(planes);
  ASSERT_TRUE(est.ok);
  ASSERT_EQ(est.H.size(), boards.size());
  EXPECT_NEAR(est.lambda_left, -7.9e-6, 1e-9 * 7.9e-6);
  EXPECT_NEAR(est.lambda_right, -7.2e-6, 1e-9 * 7.2e-6);
  for (std::size_t i = 0; i < boards.size(); ++i)
    EXPECT_LT(h_error(est.H[i], true_h(rig, t, boards[i])), 1e-10);
  EXPECT_LT(est.rms, 1e-8);
}

TEST(DivisionHomography, TooFewPointsRefused) {
  std::vector<Eigen::Vector2d> l(7, Eigen::Vector2d(1, 2)), r(7, Eigen::Vector2d(1, 2));
  EXPECT_FALSE(estimate_division_homography(l, r).ok);
}

// With corner noise the estimate degrades smoothly: the same noise pattern scaled by sigma moves lambda
// in proportion to sigma (no breakdown), the transfer RMS sits at the noise level, and 10 planes sharing
// lambda beat one plane. The small baseline makes lambda weakly observable: ~1 % per 0.01 px of noise.
TEST(DivisionHomography, DegradesGracefullyWithNoise) {
  const StereoRig rig = rig_d3();
  const BoardGeometry b;
  const Truth t = pixel_truth(rig);
  auto boards = dataset3_boards(b);
  boards.resize(10);  // enough to show the gain of sharing lambda; keeps the test quick under ASan
  std::vector<double> joint_errors;
  for (const double sigma : {0.02, 0.2}) {
    std::mt19937 rng(11);  // same pattern at every sigma
    double sq_single = 0;
    std::vector<PlaneCorrespondences> planes;
    for (const auto& s : boards) {
      planes.push_back(render(rig, t, b, s, sigma, &rng));
      const DivisionHomography h = estimate_division_homography(planes.back().left, planes.back().right);
      ASSERT_TRUE(h.ok);
      sq_single += std::pow(h.lambda_left / -7.9e-6 - 1.0, 2);
      // Symmetric transfer: each residual carries the noise of both eyes (sqrt(2) sigma), less what the
      // 10 parameters absorb.
      EXPECT_LT(h.rms, 1.8 * sigma);
      EXPECT_GT(h.rms, 1.0 * sigma);
      EXPECT_LE(h.rms, h.linear_rms * (1 + 1e-9));
    }
    const double single_rel = std::sqrt(sq_single / static_cast<double>(boards.size()));
    const DivisionLambdas joint = estimate_division_lambdas(planes);
    ASSERT_TRUE(joint.ok);
    const double rel_l = std::abs(joint.lambda_left / -7.9e-6 - 1.0);
    const double rel_r = std::abs(joint.lambda_right / -7.2e-6 - 1.0);
    std::printf(
        "sigma %.2f px: lambda rel. error, one plane (RMS of 10) %.4f; 10 planes %.5f / %.5f; rms %.4f\n",
        sigma, single_rel, rel_l, rel_r, joint.rms);
    EXPECT_LT(rel_l, 2.0 * sigma);
    EXPECT_LT(rel_r, 2.0 * sigma);
    EXPECT_LT(rel_l, single_rel);
    EXPECT_GT(joint.rms, 1.0 * sigma);
    EXPECT_LT(joint.rms, 1.5 * sigma);
    joint_errors.push_back(rel_l);
  }
  // 10x the noise gives roughly 10x the error: between 4x and 20x.
  EXPECT_GT(joint_errors[1] / joint_errors[0], 4.0);
  EXPECT_LT(joint_errors[1] / joint_errors[0], 20.0);
}
