// Naive corner plane sweep: depth by the fronto-parallel plane whose homography transfers best.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "division_scene.hpp"
#include "naneye/recon/paper/division_triangulation.hpp"
#include "naneye/recon/paper/plane_sweep.hpp"

using namespace naneye::recon;
using namespace division_test;

TEST(PlaneSweep, FindsTheDepthOnNoiseFreeData) {
  const DivisionRig rig = make_division_rig(rig_d3(), DivisionVariant::image_centre, -7.9e-6, -7.2e-6);
  const Views v = render(rig, place_board(25, -20, 70, 3, -2));
  for (const bool parabolic : {false, true}) {
    PlaneSweepSettings s;
    s.step_mm = 0.1;
    s.parabolic = parabolic;
    const auto hits = plane_sweep_division(rig, v.left, v.right, s);
    double worst = 0;
    for (std::size_t i = 0; i < hits.size(); ++i) {
      ASSERT_TRUE(hits[i].ok);
      EXPECT_FALSE(hits[i].at_range_end);
      worst = std::max(worst, std::abs(hits[i].depth_mm - v.truth[i].z()));
      // The point lies on the left ray at the chosen depth.
      EXPECT_NEAR(hits[i].X.z(), hits[i].depth_mm, 1e-12);
      EXPECT_LT((hits[i].X / hits[i].X.z() - v.truth[i] / v.truth[i].z()).norm(), 1e-12);
    }
    std::printf("step 0.1 mm, parabolic %d: worst depth error %.4g mm\n", parabolic, worst);
    // Without interpolation the error is at most half a step; the parabola through e^2 (quadratic in
    // 1/z, nearly so in z over one step) removes almost all of it.
    EXPECT_LE(worst, parabolic ? 0.005 : 0.05 + 1e-9);
  }
}

TEST(PlaneSweep, FlagsDepthsOutsideTheRange) {
  const DivisionRig rig = make_division_rig(rig_d3(), DivisionVariant::normalized, -0.37, -0.34);
  const Views v = render(rig, place_board(0, 0, 120));
  PlaneSweepSettings s;
  s.z_min_mm = 20;
  s.z_max_mm = 80;
  const auto hits = plane_sweep_division(rig, v.left, v.right, s);
  for (const auto& h : hits) {
    ASSERT_TRUE(h.ok);
    EXPECT_TRUE(h.at_range_end);
    EXPECT_DOUBLE_EQ(h.depth_mm, 80.0);
  }
  EXPECT_THROW(plane_sweep_corners(rig.pinhole(), v.left, v.right, {10, 5, 0.1, true}),
               std::invalid_argument);
}

// The paper: "the plane-sweeping approach (as it was applied) is equivalent to triangulation". With
// noise the two differ by far less than either differs from the truth.
TEST(PlaneSweep, EquivalentToTriangulationWithNoise) {
  const DivisionRig rig = make_division_rig(rig_d3(), DivisionVariant::image_centre, -7.9e-6, -7.2e-6);
  std::mt19937 rng(7);
  const Views v = render(rig, place_board(10, 15, 70), 0.2, &rng);
  const auto hits = plane_sweep_division(rig, v.left, v.right, {});
  double diff = 0, err = 0;
  int n = 0;
  const auto tri = triangulate_undistorted(rig, v.left, v.right, TriangulationMethod::niter2);
  for (std::size_t i = 0; i < hits.size(); ++i) {
    ASSERT_TRUE(tri[i].ok() && hits[i].ok);
    diff += std::abs(hits[i].depth_mm - tri[i].X.z());
    err += std::abs(tri[i].X.z() - v.truth[i].z());
    ++n;
  }
  std::printf("mean |sweep - triangulation| %.3g mm, mean |triangulation - truth| %.3g mm\n", diff / n,
              err / n);
  EXPECT_GT(err / n, 0.3);
  EXPECT_LT(diff / n, 0.2 * err / n);
}
