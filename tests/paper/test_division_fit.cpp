// The division model fitted to the polynomial Dataset 3 cameras: the model error against radius.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "division_scene.hpp"
#include "naneye/recon/paper/division_fit.hpp"

using namespace naneye::recon;
using namespace division_test;

namespace {

struct Profile {
  double inner = 0, outer = 0;  // worst residual below 60 px and beyond 110 px from the centre of distortion
};

Profile profile(const DivisionFit& f) {
  Profile p;
  for (const auto& s : f.samples) {
    if (s.radius_px < 60) p.inner = std::max(p.inner, s.residual_px);
    if (s.radius_px > 110) p.outer = std::max(p.outer, s.residual_px);
  }
  return p;
}

}  // namespace

TEST(DivisionFit, Dataset3ResidualGrowsWithRadius) {
  const StereoRig rig = rig_d3();
  for (const auto* cam : {&rig.left, &rig.right}) {
    double rms[2] = {0, 0};
    for (const auto v : {DivisionVariant::image_centre, DivisionVariant::normalized}) {
      const DivisionFit f = fit_division_to_camera(*cam, v, 4);
      ASSERT_TRUE(f.ok);
      const Profile p = profile(f);
      std::printf(
          "%s %-12s: lambda %.5g, rms %.3f px, max %.3f px, max below 60 px %.3f, beyond 110 px %.3f (%d "
          "px)\n",
          cam == &rig.left ? "left " : "right", to_string(v), f.lambda, f.rms_px, f.max_px, p.inner, p.outer,
          f.samples_used);
      rms[v == DivisionVariant::normalized] = f.rms_px;
      EXPECT_LT(f.lambda, 0.0);  // barrel
      EXPECT_LT(p.inner, 1.5);
      EXPECT_GT(p.outer, 5.0 * p.inner);
      EXPECT_GT(f.max_px, 5.0);  // one parameter cannot follow k1, k2, k3 to the image edge
      // Exactly the grid pixels inside the polynomial's domain are used (the left camera folds at 138.6 px,
      // the right one never).
      int inside = 0;
      for (int y = 0; y < 250; y += 4) {
        for (int x = 0; x < 250; x += 4) inside += cam->in_domain(Eigen::Vector2d(x, y)) ? 1 : 0;
      }
      EXPECT_EQ(f.samples_used, inside);
      EXPECT_LT(inside, cam == &rig.left ? 0.9 * 63 * 63 : 63 * 63 + 1);
      // A least-squares optimum: moving lambda either way raises the RMS.
      for (const double k : {0.99, 1.01}) {
        DivisionModel m = f.model;
        m.lambda *= k;
        EXPECT_GT(division_residuals(*cam, m, 4).rms_px, f.rms_px);
      }
    }
    // The left principal point lies 13 px from the image centre: centring there costs accuracy.
    if (cam == &rig.left) {
      EXPECT_LT(rms[1], 0.5 * rms[0]);
    }
  }
}

TEST(DivisionFit, MildDistortionIsMatchedToFirstOrder) {
  // x_d = x_n (1 + k1 r^2) and x_u = x_d / (1 + lambda r_d^2) agree to first order when lambda = k1.
  Eigen::Matrix3d K;
  K << 216.0, 0, 122.0, 0, 216.0, 112.0, 0, 0, 1;
  const CameraModel cam(K, Distortion{-0.02, 0, 0, 0, 0});
  const DivisionFit f = fit_division_to_camera(cam, DivisionVariant::normalized, 4);
  ASSERT_TRUE(f.ok);
  EXPECT_NEAR(f.lambda, -0.02, 0.002);
  EXPECT_LT(f.max_px, 0.05);
  EXPECT_GT(f.max_px, 0.0);
}
