// Triangulation of raw pixel pairs with the paper's Dataset 3 rig (config/calib/paper-d3.yaml).
#include "naneye/recon/geometry/triangulation.hpp"

#include <gtest/gtest.h>

#include <cstdio>

#include <Eigen/Core>
#include <Eigen/SVD>
#include <array>
#include <cmath>
#include <filesystem>
#include <random>
#include <vector>

#include "naneye/recon/camera/calibration_io.hpp"

namespace naneye::recon {
namespace {

StereoRig dataset3() {
  return load_rig(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml");
}

constexpr std::array<TriangulationMethod, 4> kMethods = {
    TriangulationMethod::dlt, TriangulationMethod::midpoint, TriangulationMethod::niter2,
    TriangulationMethod::refined};

bool inside_image(const CameraModel& cam, const Eigen::Vector2d& px) {
  return px.x() >= 0.0 && px.y() >= 0.0 && px.x() <= cam.width() - 1.0 && px.y() <= cam.height() - 1.0;
}

struct Truth {
  Eigen::Vector3d X;
  Eigen::Vector2d px_left, px_right;
};

// 3D points seen by both cameras: rays through a left pixel lattice over the whole valid domain,
// at depths cycling through 15..120 mm; kept when the right projection lands inside the image.
std::vector<Truth> points_over_valid_area(const StereoRig& rig, int step_px) {
  const std::array<double, 6> depths = {15.0, 30.0, 50.0, 70.0, 95.0, 120.0};
  std::vector<Truth> out;
  int k = 0;
  for (int v = 0; v < rig.left.height(); v += step_px) {
    for (int u = 0; u < rig.left.width(); u += step_px) {
      const Undistorted und = rig.left.undistort(Eigen::Vector2d(u, v));
      if (!und.ok()) continue;
      const double Z = depths[static_cast<std::size_t>(k++) % depths.size()];
      Truth t;
      t.X = Z * Eigen::Vector3d(und.normalized.x(), und.normalized.y(), 1.0);
      t.px_left = rig.left.project(t.X);
      t.px_right = rig.right.project(rig.R * t.X + rig.T);
      if (!inside_image(rig.right, t.px_right)) continue;
      out.push_back(t);
    }
  }
  return out;
}

TEST(Triangulation, NoiseFreeIsExactForEveryMethodOverTheValidArea) {
  const StereoRig rig = dataset3();
  const std::vector<Truth> truth = points_over_valid_area(rig, 7);
  ASSERT_GT(truth.size(), 900u);
  for (TriangulationMethod m : kMethods) {
    double worst = 0.0;
    for (const Truth& t : truth) {
      const Triangulated r = triangulate(rig, t.px_left, t.px_right, m, 0.2);
      ASSERT_TRUE(r.ok()) << to_string(m) << " " << to_string(r.status);
      worst = std::max(worst, (r.X - t.X).norm());
      EXPECT_GT(r.depth_sigma_mm, 0.0);
    }
    EXPECT_LE(worst, 1e-9) << to_string(m);
    std::printf("  %-8s max 3D error %.3g mm over %zu points\n", to_string(m), worst, truth.size());
  }
}

TEST(Triangulation, PixelsOutsideTheModelDomainAreRefusedWithTheSideAndReason) {
  const StereoRig rig = dataset3();
  // (0, 0) is 165 px from the left principal point, beyond the fold at 138.6 px.
  const Eigen::Vector2d corner(0.0, 0.0), centre(122.0, 111.0);
  for (TriangulationMethod m : kMethods) {
    const Triangulated r = triangulate(rig, corner, centre, m, 0.2);
    EXPECT_EQ(r.status, TriangulationStatus::left_pixel_invalid);
    EXPECT_EQ(r.left_undistort, UndistortStatus::outside_model);
    EXPECT_EQ(r.right_undistort, UndistortStatus::ok);
    EXPECT_FALSE(r.X.allFinite());
    EXPECT_FALSE(std::isfinite(r.depth_sigma_mm));
  }
  // The right Dataset 3 model never folds; give the right side the left model to see it refused.
  StereoRig folded = rig;
  folded.right = rig.left;
  Triangulated r = triangulate(folded, centre, corner, TriangulationMethod::refined, 0.2);
  EXPECT_EQ(r.status, TriangulationStatus::right_pixel_invalid);
  EXPECT_EQ(r.right_undistort, UndistortStatus::outside_model);
  EXPECT_FALSE(r.X.allFinite());
  r = triangulate(folded, corner, corner, TriangulationMethod::refined, 0.2);
  EXPECT_EQ(r.status, TriangulationStatus::left_pixel_invalid);
  EXPECT_EQ(r.left_undistort, UndistortStatus::outside_model);
  EXPECT_EQ(r.right_undistort, UndistortStatus::outside_model);
}

TEST(Triangulation, PointBehindTheCamerasIsRefused) {
  const StereoRig rig = dataset3();
  // The right pixel of a point on the left ray but 60 mm behind the rig: the rays meet there.
  const Eigen::Vector3d X(1.0, 0.5, 60.0);
  const Eigen::Vector2d pl = rig.left.project(X);
  const Eigen::Vector2d pr = rig.right.project(rig.R * -X + rig.T);
  for (TriangulationMethod m : kMethods) {
    const Triangulated r = triangulate(rig, pl, pr, m, 0.2);
    EXPECT_EQ(r.status, TriangulationStatus::behind_camera) << to_string(m);
    EXPECT_FALSE(r.X.allFinite());
  }
}

// The squared normalized-plane distance of (xl0, xr0) to the closest pair on corresponding
// epipolar lines, by brute force over the pencil of left epipolar lines (Hartley-Sturm's
// parametrisation, minimised numerically instead of by their polynomial).
struct BruteForce {
  double cost;
  Eigen::Vector2d xl, xr;
};

BruteForce brute_force_optimum(const Eigen::Matrix3d& E, const Eigen::Vector2d& xl0,
                               const Eigen::Vector2d& xr0) {
  // Left epipole: E e = 0.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(E, Eigen::ComputeFullV);
  const Eigen::Vector3d eh = svd.matrixV().col(2);
  const Eigen::Vector2d e = eh.head<2>() / eh.z();
  const auto eval = [&](double t) {
    const Eigen::Vector2d u(std::cos(t), std::sin(t));
    BruteForce b;
    b.xl = e + u * u.dot(xl0 - e);
    const Eigen::Vector3d lr = E * Eigen::Vector3d(e.x() + u.x(), e.y() + u.y(), 1.0);
    const double s = lr.head<2>().squaredNorm();
    const double dr = (lr.head<2>().dot(xr0) + lr.z()) / s;
    b.xr = xr0 - dr * lr.head<2>();
    b.cost = (b.xl - xl0).squaredNorm() + (b.xr - xr0).squaredNorm();
    return b;
  };
  // The cost is unimodal over a wide range of t around its minimum (each term grows like the
  // squared distance of a point from a line turning about the epipole), so a coarse scan brackets
  // the minimum and a golden-section search pins it down.
  const int n = 2000;
  const double pi = std::acos(-1.0);
  int best = 0;
  double best_cost = eval(0.0).cost;
  for (int i = 1; i < n; ++i) {
    const double c = eval(pi * i / n).cost;
    if (c < best_cost) {
      best_cost = c;
      best = i;
    }
  }
  const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
  double lo = pi * (best - 1) / n, hi = pi * (best + 1) / n;
  double m1 = hi - phi * (hi - lo), m2 = lo + phi * (hi - lo);
  double c1 = eval(m1).cost, c2 = eval(m2).cost;
  for (int it = 0; it < 90; ++it) {
    if (c1 < c2) {
      hi = m2;
      m2 = m1;
      c2 = c1;
      m1 = hi - phi * (hi - lo);
      c1 = eval(m1).cost;
    } else {
      lo = m1;
      m1 = m2;
      c1 = c2;
      m2 = lo + phi * (hi - lo);
      c2 = eval(m2).cost;
    }
  }
  return eval(0.5 * (lo + hi));
}

TEST(Triangulation, Niter2MatchesBruteForceOptimumWithNoise) {
  const StereoRig rig = dataset3();
  const Eigen::Matrix3d E = rig.essential();
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.5);
  const std::vector<Truth> truth = points_over_valid_area(rig, 25);
  ASSERT_GT(truth.size(), 40u);
  double worst_gap = 0.0;
  for (const Truth& t : truth) {
    const Eigen::Vector2d pl = t.px_left + Eigen::Vector2d(noise(rng), noise(rng));
    const Eigen::Vector2d pr = t.px_right + Eigen::Vector2d(noise(rng), noise(rng));
    const Undistorted ul = rig.left.undistort(pl), ur = rig.right.undistort(pr);
    if (!ul.ok() || !ur.ok()) continue;
    const CorrectedPair c = niter2_correct(E, ul.normalized, ur.normalized);
    // Our convention: xr^T E xl = 0 holds for the corrected pair.
    const double residual =
        Eigen::Vector3d(c.xr.x(), c.xr.y(), 1.0).dot(E * Eigen::Vector3d(c.xl.x(), c.xl.y(), 1.0));
    EXPECT_LE(std::abs(residual), 1e-15);
    const double cost = (c.xl - ul.normalized).squaredNorm() + (c.xr - ur.normalized).squaredNorm();
    const BruteForce b = brute_force_optimum(E, ul.normalized, ur.normalized);
    ASSERT_GT(b.cost, 0.0);
    // niter2 is Lindstrom's two-step approximation of the optimum: equal to it up to ~1e-9 of the
    // cost (it may come out marginally below, as its pair meets the constraint only to rounding).
    EXPECT_NEAR(cost / b.cost, 1.0, 1e-8);
    worst_gap = std::max(worst_gap, std::abs(cost / b.cost - 1.0));
    EXPECT_LE((c.xl - b.xl).norm(), 1e-7);
    EXPECT_LE((c.xr - b.xr).norm(), 1e-7);
  }
  std::printf("  niter2 cost differs from the brute-force optimum by at most %.3g (relative)\n", worst_gap);
}

TEST(Triangulation, RefinementLowersRawPixelReprojectionErrorAndIsStationary) {
  const StereoRig rig = dataset3();
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.3);
  const std::vector<Truth> truth = points_over_valid_area(rig, 10);
  double sum_niter2 = 0.0, sum_refined = 0.0, worst_decrease = 0.0;
  int n = 0;
  for (const Truth& t : truth) {
    const Eigen::Vector2d pl = t.px_left + Eigen::Vector2d(noise(rng), noise(rng));
    const Eigen::Vector2d pr = t.px_right + Eigen::Vector2d(noise(rng), noise(rng));
    const Undistorted ul = rig.left.undistort(pl), ur = rig.right.undistort(pr);
    if (!ul.ok() || !ur.ok()) continue;
    const Eigen::Vector3d X0 = triangulate_niter2(rig, ul.normalized, ur.normalized);
    if (!(X0.z() > 0.0)) continue;
    const Eigen::Vector3d X1 = refine_reprojection(rig, X0, pl, pr);
    const double c0 = reprojection_residual(rig, X0, pl, pr).squaredNorm();
    const Eigen::Vector4d r1 = reprojection_residual(rig, X1, pl, pr);
    EXPECT_LE(r1.squaredNorm(), c0 * (1.0 + 1e-12));
    // A minimum of the raw-pixel cost: the decrease a further Gauss-Newton step predicts,
    // g^T (J^T J)^-1 g with g = J^T r, is nil next to the cost.
    const Eigen::Matrix<double, 4, 3> J = reprojection_jacobian(rig, X1);
    const Eigen::Vector3d g = J.transpose() * r1;
    const double predicted_decrease = g.dot((J.transpose() * J).ldlt().solve(g));
    worst_decrease = std::max(worst_decrease, predicted_decrease / r1.squaredNorm());
    EXPECT_LE(predicted_decrease, 1e-12 * r1.squaredNorm()) << X0.transpose() << " -> " << X1.transpose();
    sum_niter2 += std::sqrt(c0);
    sum_refined += r1.norm();
    ++n;
  }
  ASSERT_GT(n, 300);
  std::printf(
      "  mean raw-pixel residual: niter2 %.6f px, refined %.6f px; worst predicted relative decrease %.3g\n",
      sum_niter2 / n, sum_refined / n, worst_decrease);
  EXPECT_LT(sum_refined, 0.999 * sum_niter2);
}

TEST(Triangulation, JacobianMatchesFiniteDifferences) {
  const StereoRig rig = dataset3();
  const Eigen::Vector3d X(-9.0, 7.5, 25.0);
  const Eigen::Matrix<double, 4, 3> J = reprojection_jacobian(rig, X);
  const Eigen::Vector2d zero(0.0, 0.0);
  for (int k = 0; k < 3; ++k) {
    const double h = 1e-6;
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d(k) = h;
    const Eigen::Vector4d num =
        (reprojection_residual(rig, X + d, zero, zero) - reprojection_residual(rig, X - d, zero, zero)) /
        (2 * h);
    EXPECT_LE((num - J.col(k)).norm(), 1e-5 * J.col(k).norm());
  }
}

TEST(Triangulation, DepthSigmaAgreesWithMonteCarloSpread) {
  const StereoRig rig = dataset3();
  const double sigma = 0.1;
  std::mt19937 rng(2016);
  std::normal_distribution<double> noise(0.0, sigma);
  // Centre near, edge far; 1200 trials each pin the spread down to ~2 %.
  const std::array<Eigen::Vector3d, 2> points = {Eigen::Vector3d(0.5, -0.3, 30.0),
                                                 Eigen::Vector3d(-25.0, 18.0, 60.0)};
  for (const Eigen::Vector3d& X : points) {
    const Eigen::Vector2d pl = rig.left.project(X), pr = rig.right.project(rig.R * X + rig.T);
    ASSERT_TRUE(rig.left.in_domain(pl));
    const double predicted = depth_sigma_mm(rig, X, sigma);
    const int trials = 1200;
    double sum = 0.0, sum2 = 0.0, sum_reported = 0.0;
    int n = 0;
    for (int i = 0; i < trials; ++i) {
      const Triangulated r =
          triangulate(rig, pl + Eigen::Vector2d(noise(rng), noise(rng)),
                      pr + Eigen::Vector2d(noise(rng), noise(rng)), TriangulationMethod::refined, sigma);
      ASSERT_TRUE(r.ok());
      sum_reported += r.depth_sigma_mm;
      sum += r.X.z();
      sum2 += r.X.z() * r.X.z();
      ++n;
    }
    const double mean = sum / n;
    const double spread = std::sqrt((sum2 - n * mean * mean) / (n - 1));
    std::printf("  X (%.1f, %.1f, %.1f): predicted depth sigma %.4f mm, Monte-Carlo %.4f mm\n", X.x(), X.y(),
                X.z(), predicted, spread);
    EXPECT_NEAR(spread, predicted, 0.10 * predicted) << "X = " << X.transpose();
    // The sigma each triangulation reports (evaluated at its own noisy point) averages to the same.
    EXPECT_NEAR(sum_reported / n, predicted, 0.03 * predicted);
  }
}

}  // namespace
}  // namespace naneye::recon
