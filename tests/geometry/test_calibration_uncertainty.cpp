// CalibrationUncertainty against what it claims: its parameter Jacobian against finite differences
// of CameraModel::project on perturbed rigs, and its point covariance against the spread of points
// re-triangulated (refined) from the same pixels with rigs drawn from the covariance (Monte Carlo,
// mrcal's check of its projection uncertainty).
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <random>

#include "../support/correlated_covariance.hpp"
#include "../support/paper_rig.hpp"
#include "naneye/recon/geometry/calibration_uncertainty.hpp"
#include "naneye/recon/geometry/triangulation.hpp"

namespace naneye::recon {
namespace calibration_uncertainty_test {

using Params = Eigen::Matrix<double, kCalibrationParameters, 1>;

// The rig with its parameters moved by dp (rig.hpp's order).
StereoRig perturbed(const StereoRig& rig, const Params& dp) {
  const auto camera = [&](const CameraModel& c, int first) {
    Eigen::Matrix3d K = c.K();
    K(0, 0) += dp(first);
    K(1, 1) += dp(first + 1);
    K(0, 2) += dp(first + 2);
    K(1, 2) += dp(first + 3);
    const Distortion& d = c.distortion();
    const Distortion moved{d.k1 + dp(first + 4), d.k2 + dp(first + 5), d.p1 + dp(first + 6),
                           d.p2 + dp(first + 7), d.k3 + dp(first + 8)};
    return CameraModel(K, moved, c.width(), c.height());
  };
  StereoRig out = rig;
  out.left = camera(rig.left, kCalibrationLeft);
  out.right = camera(rig.right, kCalibrationRight);
  out.R = rodrigues(Eigen::Vector3d(rodrigues(rig.R) + dp.segment<3>(kCalibrationOm)));
  out.T = rig.T + dp.segment<3>(kCalibrationT);
  return out;
}

// Points over the view both eyes see, 8-70 mm (the scene paths' range).
std::vector<Eigen::Vector3d> points() {
  return {{0.0, 0.0, 20.0}, {-3.0, 2.0, 12.0},  {5.0, -4.0, 25.0},
          {0.5, 0.3, 8.0},  {20.0, 15.0, 70.0}, {-25.0, 10.0, 60.0}};
}

TEST(CalibrationUncertainty, ParameterJacobianMatchesFiniteDifferences) {
  StereoRig rig = test::paper_d3();
  // Tangential terms and a skew, so that every column is exercised.
  Eigen::Matrix3d K = rig.left.K();
  K(0, 1) = 0.3;
  const Distortion d = rig.left.distortion();
  rig.left = CameraModel(K, Distortion{d.k1, d.k2, 2e-3, -1e-3, d.k3}, 250, 250);
  // The paper's file has sigmas but no covariance: no sigma to give, only the what-if.
  EXPECT_FALSE(CalibrationUncertainty::of(rig).has_value());
  const auto u = CalibrationUncertainty::assuming_independent_sigmas(rig);
  ASSERT_TRUE(u.has_value());
  EXPECT_EQ(u->basis(), CalibrationUncertainty::Basis::independent_sigmas);
  for (const Eigen::Vector3d& X : points()) {
    const auto J = u->parameter_jacobian(X);
    for (int k = 0; k < kCalibrationParameters; ++k) {
      const double h = 1e-6;
      Params dp = Params::Zero();
      dp(k) = h;
      const StereoRig a = perturbed(rig, dp), b = perturbed(rig, -dp);
      Eigen::Vector4d num;
      num << (a.left.project(X) - b.left.project(X)) / (2 * h),
          (a.right.project(Eigen::Vector3d(a.R * X + a.T)) -
           b.right.project(Eigen::Vector3d(b.R * X + b.T))) /
              (2 * h);
      for (int r = 0; r < 4; ++r)
        EXPECT_NEAR(J(r, k), num(r), 1e-6 * std::max(1.0, std::abs(num(r))))
            << "parameter " << k << " row " << r;
    }
  }
}

// The spread of re-triangulated points is the predicted one: 2000 draws, the sample sd within 7 %
// (its own relative sd is 1/sqrt(2 * 2000) = 1.6 %), at sigmas a tenth of the paper's, where the
// first order holds.
TEST(CalibrationUncertainty, PredictsTheSpreadOfPointsTriangulatedWithDrawnRigs) {
  StereoRig rig = test::paper_d3();
  rig.sigmas.covariance = test::correlated_covariance(rig, 0.1, 7);
  const auto u = CalibrationUncertainty::of(rig);
  ASSERT_TRUE(u.has_value());
  EXPECT_EQ(u->basis(), CalibrationUncertainty::Basis::full_covariance);
  const Eigen::LLT<CalibrationCovariance> llt(*rig.sigmas.covariance);
  ASSERT_EQ(llt.info(), Eigen::Success);
  const CalibrationCovariance L = llt.matrixL();
  std::mt19937 rng(11);
  std::normal_distribution<double> n;
  constexpr int kDraws = 2000;
  std::vector<StereoRig> drawn;
  drawn.reserve(kDraws);
  for (int i = 0; i < kDraws; ++i) {
    Params z;
    for (int k = 0; k < kCalibrationParameters; ++k) z(k) = n(rng);
    drawn.push_back(perturbed(rig, L * z));
  }
  for (const Eigen::Vector3d& X : points()) {
    const Eigen::Vector2d pl = rig.left.project(X),
                          pr = rig.right.project(Eigen::Vector3d(rig.R * X + rig.T));
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
    int ok = 0;
    for (const StereoRig& r : drawn) {
      const Triangulated t = triangulate(r, pl, pr, TriangulationMethod::refined, 0.1);
      if (!t.ok()) continue;
      ++ok;
      mean += t.X;
      second += t.X * t.X.transpose();
    }
    ASSERT_EQ(ok, kDraws);
    mean /= ok;
    const Eigen::Matrix3d sample = second / ok - mean * mean.transpose();
    const Eigen::Matrix3d predicted = u->point_covariance(X);
    const double ratio = std::sqrt(sample(2, 2) / predicted(2, 2));
    std::printf(
        "X (%.1f, %.1f, %.1f) mm: calibration depth sigma %.4f mm predicted, %.4f mm drawn (ratio %.3f)\n",
        X.x(), X.y(), X.z(), std::sqrt(predicted(2, 2)), std::sqrt(sample(2, 2)), ratio);
    EXPECT_NEAR(ratio, 1.0, 0.07);
    EXPECT_NEAR(u->depth_sigma_mm(X), std::sqrt(predicted(2, 2)), 1e-12 * std::sqrt(predicted(2, 2)));
    for (int a = 0; a < 2; ++a)
      EXPECT_NEAR(std::sqrt(sample(a, a) / predicted(a, a)), 1.0, 0.07) << "axis " << a;
  }
}

TEST(CalibrationUncertainty, AbsentWithoutSigmas) {
  StereoRig rig = test::paper_d3();
  rig.sigmas = {};
  EXPECT_FALSE(CalibrationUncertainty::of(rig).has_value());
  EXPECT_FALSE(CalibrationUncertainty::assuming_independent_sigmas(rig).has_value());
}

// The cross-validation's scale (rig.hpp covariance_scale) widens every full-covariance sigma by
// exactly its factor and leaves the what-if from the marginals alone.
TEST(CalibrationUncertainty, TheCrossValidationScaleWidensEverySigmaByItsFactor) {
  StereoRig rig = test::paper_d3();
  rig.sigmas.covariance = test::correlated_covariance(rig, 1.0, 3);
  const auto plain = CalibrationUncertainty::of(rig);
  const auto marginals = CalibrationUncertainty::assuming_independent_sigmas(rig);
  rig.sigmas.covariance_scale = 2.5;
  const auto scaled = CalibrationUncertainty::of(rig);
  const auto marginals_scaled = CalibrationUncertainty::assuming_independent_sigmas(rig);
  ASSERT_TRUE(plain && scaled && marginals && marginals_scaled);
  for (const Eigen::Vector3d& X : points()) {
    EXPECT_NEAR(scaled->depth_sigma_mm(X), 2.5 * plain->depth_sigma_mm(X), 1e-12 * plain->depth_sigma_mm(X));
    EXPECT_EQ(marginals_scaled->depth_sigma_mm(X), marginals->depth_sigma_mm(X));
  }
}

}  // namespace calibration_uncertainty_test
}  // namespace naneye::recon
