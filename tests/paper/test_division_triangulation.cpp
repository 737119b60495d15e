// Triangulation with distorted coordinates (paper Eq. 10) against undistort-then-triangulate.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "division_scene.hpp"
#include "naneye/recon/paper/division_triangulation.hpp"

using namespace naneye::recon;
using namespace division_test;

namespace {

std::vector<DivisionRig> both_variants() {
  const StereoRig rig = rig_d3();
  return {make_division_rig(rig, DivisionVariant::image_centre, -7.9e-6, -7.2e-6),
          make_division_rig(rig, DivisionVariant::normalized, -0.37, -0.34)};
}

}  // namespace

TEST(DivisionTriangulation, DirectIsExactOnNoiseFreeData) {
  for (const DivisionRig& rig : both_variants()) {
    for (const auto& s : {place_board(0, 0, 70), place_board(30, -25, 55, 4, 2), place_board(-20, 35, 85)}) {
      const Views v = render(rig, s);
      for (const DirectSolve solve : {DirectSolve::per_point, DirectSolve::one_svd}) {
        const DirectTriangulation d = triangulate_distorted(rig, v.left, v.right, solve);
        ASSERT_TRUE(d.ok);
        for (std::size_t i = 0; i < v.truth.size(); ++i) {
          ASSERT_TRUE(d.valid[i]);
          EXPECT_LT((d.points[i] - v.truth[i]).norm(), 1e-9) << to_string(solve) << " " << i;
          // alpha2 is the depth divided by the lifted point's third coordinate (Eq. 10, x_d = (.., 1 + lambda
          // r^2)).
          EXPECT_NEAR(d.alpha2[i] * rig.left.ray(v.left[i]).z(), v.truth[i].z(), 1e-9);
        }
      }
      // The paper's claim, noise-free: identical to undistorting first and triangulating.
      for (const auto m :
           {TriangulationMethod::dlt, TriangulationMethod::midpoint, TriangulationMethod::niter2}) {
        const auto t = triangulate_undistorted(rig, v.left, v.right, m);
        for (std::size_t i = 0; i < v.truth.size(); ++i) {
          ASSERT_TRUE(t[i].ok());
          EXPECT_LT((t[i].X - v.truth[i]).norm(), 1e-9) << to_string(m);
        }
      }
    }
  }
}

// With noise, the per-point solve is the same linear estimate as solving z (x_l, 1) on the undistorted
// points (intersect_corrected): the division only rescales x_d and x'_d. The single SVD weights the
// points differently and lands close, not identical.
TEST(DivisionTriangulation, PerPointEqualsUndistortThenLinearEvenWithNoise) {
  std::mt19937 rng(5);
  for (const DivisionRig& rig : both_variants()) {
    const Views v = render(rig, place_board(15, 20, 70), 0.2, &rng);
    const DirectTriangulation pp = triangulate_distorted(rig, v.left, v.right, DirectSolve::per_point);
    const DirectTriangulation svd = triangulate_distorted(rig, v.left, v.right, DirectSolve::one_svd);
    const StereoRig pin = rig.pinhole();
    double max_diff = 0, max_svd = 0, max_err = 0;
    for (std::size_t i = 0; i < v.truth.size(); ++i) {
      ASSERT_TRUE(pp.valid[i] && svd.valid[i]);
      const Eigen::Vector3d X =
          intersect_corrected(pin, {*rig.left.normalized(v.left[i]), *rig.right.normalized(v.right[i])});
      max_diff = std::max(max_diff, (X - pp.points[i]).norm());
      max_svd = std::max(max_svd, (svd.points[i] - pp.points[i]).norm());
      max_err = std::max(max_err, (pp.points[i] - v.truth[i]).norm());
    }
    std::printf("%s: per-point vs undistort+linear %.2g mm, one SVD vs per-point %.3g mm, error %.3g mm\n",
                to_string(rig.left.model.A(0, 0) == 1.0 ? DivisionVariant::image_centre
                                                        : DivisionVariant::normalized),
                max_diff, max_svd, max_err);
    EXPECT_LT(max_diff, 1e-9);
    EXPECT_GT(max_err, 0.1);            // the noise is visible at 70 mm with a 1 mm baseline...
    EXPECT_LT(max_svd, 0.5 * max_err);  // ...and the single SVD stays well inside it
  }
}

TEST(DivisionTriangulation, PixelsOutsideTheDomainAreRefused) {
  const StereoRig rig = rig_d3();
  // lambda = -1e-4 px^-2: the denominator vanishes 100 px from the centre.
  const DivisionRig d = make_division_rig(rig, DivisionVariant::image_centre, -1e-4, -7.2e-6);
  const std::vector<Eigen::Vector2d> l{{130, 120}, {240, 240}}, r{{127, 121}, {238, 239}};
  const DirectTriangulation t = triangulate_distorted(d, l, r, DirectSolve::one_svd);
  ASSERT_TRUE(t.ok);
  EXPECT_TRUE(t.valid[0]);
  EXPECT_FALSE(t.valid[1]);
  EXPECT_TRUE(std::isnan(t.points[1].x()));
  const Triangulated u = triangulate_undistorted(d, l[1], r[1], TriangulationMethod::dlt);
  EXPECT_EQ(u.status, TriangulationStatus::left_pixel_invalid);
  EXPECT_TRUE(std::isnan(u.X.x()));
}
