// The division model (paper Eq. 7): closed-form undistortion, its inverse, the valid domain.
#include <gtest/gtest.h>

#include <cmath>

#include "division_scene.hpp"

using namespace naneye::recon;

TEST(DivisionModel, ImageCentreFollowsPixelCentresAtIntegers) {
  const DivisionModel m = DivisionModel::image_centred(-8e-6, 250, 250);
  EXPECT_EQ(m.to_model({124.5, 124.5}), Eigen::Vector2d(0, 0));
  EXPECT_EQ(m.to_pixel({-124.5, 125.5}), Eigen::Vector2d(0, 250));
  // The centre is a fixed point of both directions.
  EXPECT_EQ(*m.undistort_pixel({124.5, 124.5}), Eigen::Vector2d(124.5, 124.5));
}

TEST(DivisionModel, UndistortIsEquation7) {
  const DivisionModel m = DivisionModel::image_centred(-8e-6);
  const Eigen::Vector2d px(230.0, 20.0);
  const Eigen::Vector2d xd = px - Eigen::Vector2d(124.5, 124.5);
  const double w = 1.0 - 8e-6 * xd.squaredNorm();
  EXPECT_NEAR(w, 0.823596, 1e-9);
  const Eigen::Vector2d expected = Eigen::Vector2d(124.5, 124.5) + xd / w;
  EXPECT_LT((*m.undistort_pixel(px) - expected).norm(), 1e-12);
  // Barrel distortion (lambda < 0) pushes points outward when undistorting.
  EXPECT_GT((*m.undistort_pixel(px) - Eigen::Vector2d(124.5, 124.5)).norm(), xd.norm() * 1.2);
  const Eigen::Vector3d h = m.lift(xd);
  EXPECT_NEAR(h.z(), w, 1e-15);
}

TEST(DivisionModel, DistortInvertsUndistortInsideTheDomain) {
  for (double lambda : {-0.4, -0.05, 0.0, 0.05, 0.3}) {
    const DivisionModel m = DivisionModel::normalized(lambda, Eigen::Matrix3d::Identity());
    const double rmax = m.max_distorted_radius().value_or(5.0);
    for (double f : {0.0, 0.01, 0.3, 0.7, 0.95, 0.999}) {
      const Eigen::Vector2d xd = Eigen::Vector2d(0.6, -0.8) * (f * rmax);
      const auto xu = m.undistort(xd);
      ASSERT_TRUE(xu) << lambda << " " << f;
      const auto back = m.distort(*xu);
      ASSERT_TRUE(back);
      EXPECT_LT((*back - xd).norm(), 1e-12 * std::max(1.0, xu->norm())) << lambda << " " << f;
    }
  }
}

TEST(DivisionModel, RootIsTheOneContinuousWithLambdaToZero) {
  // As lambda -> 0 the distorted radius must tend to the undistorted one (the other root of
  // r_u lambda r_d^2 - r_d + r_u = 0 escapes to 1 / (lambda r_u)).
  for (double lambda : {1e-3, 1e-8, 1e-14, -1e-14, -1e-8, -1e-3}) {
    const auto rd = division_distort_radius(lambda, 0.7);
    ASSERT_TRUE(rd);
    EXPECT_NEAR(*rd, 0.7, 2.0 * std::abs(lambda) * 0.7 * 0.7 * 0.7 + 1e-16) << lambda;
  }
  EXPECT_EQ(*division_distort_radius(0.0, 0.7), 0.7);
}

TEST(DivisionModel, DomainEdges) {
  // lambda < 0: the denominator vanishes at r_d = 1 / sqrt(-lambda); every undistorted radius has a
  // distorted image strictly inside.
  const DivisionModel barrel = DivisionModel::normalized(-0.25, Eigen::Matrix3d::Identity());
  EXPECT_DOUBLE_EQ(*barrel.max_distorted_radius(), 2.0);
  EXPECT_TRUE(barrel.undistort({1.99, 0.0}));
  EXPECT_FALSE(barrel.undistort({2.0, 0.0}));
  EXPECT_FALSE(barrel.undistort({0.0, -3.0}));
  const auto far = barrel.distort({1e6, 0.0});
  ASSERT_TRUE(far);
  EXPECT_LT(far->x(), 2.0);
  EXPECT_GT(far->x(), 1.99);
  // lambda > 0: r_u = r_d / (1 + lambda r_d^2) peaks at r_d = 1 / sqrt(lambda) with r_u = 1 / (2
  // sqrt(lambda)); beyond that no real root.
  const DivisionModel pin = DivisionModel::normalized(0.25, Eigen::Matrix3d::Identity());
  EXPECT_TRUE(pin.distort({0.999, 0.0}));
  EXPECT_NEAR(pin.distort({1.0, 0.0})->x(), 2.0, 1e-12);
  EXPECT_FALSE(pin.distort({1.001, 0.0}));
  EXPECT_FALSE(pin.undistort({2.5, 0.0}));  // beyond the peak: folded
  EXPECT_FALSE(pin.undistort({std::nan(""), 0.0}));
}

TEST(DivisionModel, NormalizedVariantUsesK) {
  const StereoRig rig = division_test::rig_d3();
  const DivisionModel m = DivisionModel::normalized(-0.37, rig.left.K());
  const Eigen::Vector2d px(200.0, 40.0);
  const Eigen::Vector2d xd = rig.left.from_pixel(px);
  EXPECT_LT((m.to_model(px) - xd).norm(), 1e-15);
  const Eigen::Vector2d xu = xd / (1.0 - 0.37 * xd.squaredNorm());
  EXPECT_LT((*m.undistort_pixel(px) - rig.left.to_pixel(xu)).norm(), 1e-12);
  EXPECT_LT((*m.distort_pixel(*m.undistort_pixel(px)) - px).norm(), 1e-11);
  EXPECT_THROW(DivisionModel::normalized(0.1, Eigen::Matrix3d::Zero()), std::invalid_argument);
}
