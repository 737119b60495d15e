// The paper's evaluation criteria (Sec. 4.1) and its cross-validation RANSAC / median filter,
// against cases computed by hand.
#include "naneye/recon/geometry/metrics.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <limits>
#include <random>
#include <vector>

#include "naneye/recon/camera/calibration_io.hpp"

namespace naneye::recon {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A tilted plane 70 mm in front of the rig: unit normal n, in-plane axes u, v, origin point p0.
struct Frame {
  Eigen::Vector3d n, u, v, p0;
};

Frame tilted_plane() {
  const Eigen::Matrix3d rot =
      (Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(-0.25, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  return {rot.col(2), rot.col(0), rot.col(1), Eigen::Vector3d(1.5, -2.0, 70.0)};
}

// rows x cols grid of pitch `square` on the plane, row-major.
std::vector<Eigen::Vector3d> grid_on(const Frame& f, int rows, int cols, double square) {
  std::vector<Eigen::Vector3d> g;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) g.push_back(f.p0 + c * square * f.u + r * square * f.v);
  }
  return g;
}

TEST(Metrics, PlanarityOfACheckerboardOfOffsetsIsTheOffset) {
  // A 4x4 grid with offsets +d / -d along the normal in a checkerboard pattern: the offsets have
  // zero mean and no correlation with the in-plane coordinates, so the least-squares plane is the
  // true plane and every point is exactly d from it: P = d.
  const Frame f = tilted_plane();
  const double d = 0.3;
  std::vector<Eigen::Vector3d> pts = grid_on(f, 4, 4, 5.99);
  for (int i = 0; i < 16; ++i) pts[i] += ((i / 4 + i % 4) % 2 == 0 ? d : -d) * f.n;
  const auto plane = fit_plane(pts);
  ASSERT_TRUE(plane);
  EXPECT_NEAR(std::abs(plane->normal.dot(f.n)), 1.0, 1e-12);
  EXPECT_NEAR(std::abs(plane->signed_distance(f.p0)), 0.0, 1e-9);
  const auto P = planarity_error(pts);
  ASSERT_TRUE(P);
  EXPECT_NEAR(*P, d, 1e-12);

  // Invalid points are skipped, not counted as zero distance.
  pts.push_back(Eigen::Vector3d(kNaN, 0.0, 0.0));
  EXPECT_NEAR(*planarity_error(pts), d, 1e-12);
}

TEST(Metrics, PlanarityNeedsThreeNonCollinearPoints) {
  const std::vector<Eigen::Vector3d> line = {{0, 0, 1}, {1, 1, 2}, {2, 2, 3}, {3, 3, 4}};
  EXPECT_FALSE(fit_plane(line));
  EXPECT_FALSE(planarity_error(line));
  const std::vector<Eigen::Vector3d> two = {{0, 0, 1}, {1, 0, 1}, {kNaN, 0, 1}};
  EXPECT_FALSE(planarity_error(two));
}

TEST(Metrics, DistanceErrorOfAGridWithOneStretchedCorner) {
  const Frame f = tilted_plane();
  const double s = 5.99, e = 0.4;
  const int rows = 3, cols = 4;
  std::vector<Eigen::Vector3d> g = grid_on(f, rows, cols, s);
  EXPECT_NEAR(*distance_error(g, rows, cols, s), 0.0, 1e-12);
  // Moving the top-right corner outward along its row stretches the last horizontal edge of row 0
  // by e and tilts the last vertical edge of column 3 to length sqrt(s^2 + e^2).
  g[cols - 1] += e * f.u;
  const int pairs = rows * (cols - 1) + cols * (rows - 1);  // 17
  const double expected = (e + (std::sqrt(s * s + e * e) - s)) / pairs;
  EXPECT_NEAR(*distance_error(g, rows, cols, s), expected, 1e-12);
  // An invalid point removes its (up to four) pairs from the average: g[5] = (row 1, col 1) has
  // four neighbours, none of them the moved corner.
  g[5] = Eigen::Vector3d::Constant(kNaN);
  EXPECT_NEAR(*distance_error(g, rows, cols, s), (e + (std::sqrt(s * s + e * e) - s)) / (pairs - 4), 1e-12);
  EXPECT_THROW(distance_error(g, rows, cols + 1, s), std::invalid_argument);
}

TEST(Metrics, MedianFilterOfThree) {
  const std::vector<double> v = {5.0, 0.0, 0.0, 9.0, 0.0, 1.0, 2.0};
  const std::vector<double> m = median_filter3(v);
  // Ends repeat their value: median(5, 5, 0) = 5; median(1, 2, 2) = 2.
  const std::vector<double> expected = {5.0, 0.0, 0.0, 0.0, 1.0, 1.0, 2.0};
  EXPECT_EQ(m, expected);
  EXPECT_TRUE(median_filter3(std::vector<double>{}).empty());
  EXPECT_EQ(median_filter3(std::vector<double>{3.0}), std::vector<double>{3.0});
}

TEST(Metrics, MedianFilteredDistanceErrorRemovesASingleBadEdge) {
  // One row of 6 points: 5 horizontal pairs. Shortening the middle edge (moving points 3..5 by -e
  // along the row) gives errors (0, 0, e, 0, 0): D = e / 5, the median-filtered D = 0.
  const Frame f = tilted_plane();
  const double s = 2.189, e = 0.5;
  std::vector<Eigen::Vector3d> g = grid_on(f, 1, 6, s);
  for (int i = 3; i < 6; ++i) g[i] -= e * f.u;
  EXPECT_NEAR(*distance_error(g, 1, 6, s), e / 5.0, 1e-12);
  EXPECT_NEAR(*distance_error_median_filtered(g, 1, 6, s), 0.0, 1e-12);

  // A 3x3 grid: the invalid centre drops its four pairs; moving a corner spoils two consecutive
  // errors of its column, which a window of 3 keeps (our reading of the filter: one bad edge goes,
  // a bad corner stays).
  std::vector<Eigen::Vector3d> h = grid_on(f, 3, 3, s);
  h[5] += e * f.u;  // (1, 2): tilts (0,2)-(1,2) and (1,2)-(2,2); (1,1)-(1,2) is dropped
  h[4] = Eigen::Vector3d::Constant(kNaN);
  const double tilt = std::sqrt(s * s + e * e) - s;
  // Valid pairs: row 0 (2), row 2 (2), column 0 (2), column 2 (2): 8. Column 2's errors are
  // (tilt, tilt), unchanged by the filter; the others are 0.
  EXPECT_NEAR(*distance_error(h, 3, 3, s), 2.0 * tilt / 8.0, 1e-12);
  EXPECT_NEAR(*distance_error_median_filtered(h, 3, 3, s), 2.0 * tilt / 8.0, 1e-12);
}

TEST(Metrics, ReprojectionErrorIsTheMeanPixelDistanceOverBothImages) {
  const StereoRig rig = load_rig(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml");
  const std::vector<Eigen::Vector3d> X = {{0.0, 0.0, 50.0}, {3.0, -2.0, 60.0}, {kNaN, 0.0, 50.0}};
  std::vector<Eigen::Vector2d> pl, pr;
  for (const auto& p : X) {
    pl.push_back(rig.left.project(p));
    pr.push_back(rig.right.project(rig.R * p + rig.T));
  }
  EXPECT_NEAR(*reprojection_error(rig, X, pl, pr), 0.0, 1e-12);
  // Offsets of 0.3 and 0.4 px (a 3-4-5 triangle: 0.5 px) on one left pixel, 1 px on one right
  // pixel: (0.5 + 1.0) / 4 observations.
  pl[0] += Eigen::Vector2d(0.3, 0.4);
  pr[1] += Eigen::Vector2d(0.0, -1.0);
  EXPECT_NEAR(*reprojection_error(rig, X, pl, pr), 1.5 / 4.0, 1e-12);
  pl.pop_back();
  EXPECT_THROW(reprojection_error(rig, X, pl, pr), std::invalid_argument);
}

TEST(Metrics, RansacRejectsAPlantedOutlierExhaustively) {
  // 48 corners (6 x 8, the paper's boards) on the tilted plane at ~70 mm with small known offsets;
  // one corner pulled 12 mm off the plane (beyond 15 % of ~67 mm). The plain fit is pulled
  // towards it, the RANSAC fit is not.
  const Frame f = tilted_plane();
  std::vector<Eigen::Vector3d> pts = grid_on(f, 6, 8, 5.99);
  for (std::size_t i = 0; i < pts.size(); ++i) pts[i] += ((i % 2) ? 0.05 : -0.05) * f.n;
  const std::size_t outlier = 19;
  pts[outlier] += 12.0 * f.n;
  pts.push_back(Eigen::Vector3d::Constant(kNaN));

  const Plane truth{f.n, -f.n.dot(f.p0)};
  const auto plain = fit_plane(pts);
  ASSERT_TRUE(plain);
  const auto robust = fit_plane_ransac(pts);
  ASSERT_TRUE(robust);
  EXPECT_EQ(robust->inlier_count, 47);
  EXPECT_FALSE(robust->inliers[outlier]);
  EXPECT_FALSE(robust->inliers.back());  // the invalid point
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
    if (i != outlier) {
      EXPECT_TRUE(robust->inliers[i]) << i;
    }
  }
  EXPECT_GT(std::abs(robust->plane.normal.dot(truth.normal)), std::abs(plain->normal.dot(truth.normal)));
  EXPECT_NEAR(std::abs(robust->plane.normal.dot(truth.normal)), 1.0, 1e-4);
  EXPECT_LT(robust->mean_inlier_distance, 0.06);
  EXPECT_GT(*planarity_error(pts), 0.2);
}

TEST(Metrics, RansacWithRandomTriplesIsSeededAndFindsThePlane) {
  // 100 points (> 64: random triples) of which 20 are scattered far off the plane.
  const Frame f = tilted_plane();
  std::vector<Eigen::Vector3d> pts = grid_on(f, 10, 10, 2.0);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> off(15.0, 40.0);
  std::vector<bool> planted(pts.size(), false);
  for (std::size_t i = 0; i < pts.size(); i += 5) {
    pts[i] += off(rng) * f.n;
    planted[i] = true;
  }
  const auto a = fit_plane_ransac(pts);
  const auto b = fit_plane_ransac(pts);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->inliers, b->inliers);
  EXPECT_EQ(a->inlier_count, 80);
  for (std::size_t i = 0; i < pts.size(); ++i) EXPECT_EQ(a->inliers[i], !planted[i]) << i;
  EXPECT_NEAR(std::abs(a->plane.normal.dot(f.n)), 1.0, 1e-12);
  EXPECT_NEAR(a->mean_inlier_distance, 0.0, 1e-9);
}

}  // namespace
}  // namespace naneye::recon
