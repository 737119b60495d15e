// The textured-scene simulator's truth (sim/textured.hpp) against the analytic surfaces.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <stdexcept>

#include "scene_fixture.hpp"

namespace naneye {
namespace {

using sim::SurfaceKind;

// Distance of a point from the analytic surface (plane, sphere, tube wall or end, height field).
double surface_residual(const sim::Surface& s, const Eigen::Vector3d& X) {
  switch (s.kind) {
    case SurfaceKind::plane:
      return s.axis.dot(X - s.origin);
    case SurfaceKind::sphere:
      return (X - s.origin).norm() - s.radius_mm;
    case SurfaceKind::tube: {
      const Eigen::Vector3d p = X - s.origin;
      const double along = p.dot(s.axis);
      const double wall = (p - along * s.axis).norm() - s.radius_mm;
      return std::min(std::abs(wall), std::abs(along - 80.0));
    }
    case SurfaceKind::height_field: {
      double h = 0;
      for (const auto& w : s.waves) h += w.amp_mm * std::sin(w.kx * X.x() + w.ky * X.y() + w.phase);
      return X.z() - s.origin.z() - h;
    }
  }
  return NAN;
}

TEST(TexturedSim, TruthLiesOnTheSurfaceAndBothEyesSeeIt) {
  const auto& rig = test::paper_d3();
  const auto& r = test::textured_renderer(false);
  for (const auto& name : sim::textured_preset_names()) {
    const auto scene = *sim::textured_preset(name);
    const cv::Mat depth = r.truth_depth(scene.surface);
    int with = 0, beyond_fold = 0, one_eye = 0;
    double zmin = 1e9, zmax = 0;
    for (int v = 0; v < 250; ++v)
      for (int u = 0; u < 250; ++u) {
        const double z = depth.at<double>(v, u);
        const recon::Undistorted ul = rig.left.undistort(Eigen::Vector2d(u, v));
        if (!ul.ok()) {
          EXPECT_TRUE(std::isnan(z)) << name << " beyond the fold at " << u << "," << v;
          ++beyond_fold;
          continue;
        }
        if (std::isnan(z)) {
          ++one_eye;
          continue;
        }
        ++with;
        zmin = std::min(zmin, z);
        zmax = std::max(zmax, z);
        const Eigen::Vector3d X(ul.normalized.x() * z, ul.normalized.y() * z, z);
        ASSERT_LT(std::abs(surface_residual(scene.surface, X)), 1e-7) << name << " " << u << "," << v;
        const Eigen::Vector2d pr = rig.right.project(rig.R * X + rig.T);
        ASSERT_TRUE(pr.x() >= -0.5 && pr.x() <= 248.5 && pr.y() >= -0.5 && pr.y() <= 248.5) << name;
      }
    std::printf("%-10s truth on %5d px, %.1f-%.1f mm; %d px one eye or none, %d beyond the left fold\n",
                name.c_str(), with, zmin, zmax, one_eye, beyond_fold);
    EXPECT_GT(with, 20000) << name;
    // The eyes' views differ by the 11 px offset of their principal points and the rig's rotation:
    // part of the left view has no right counterpart, and the truth says so.
    EXPECT_GT(one_eye, 1000) << name;
    EXPECT_GT(zmin, 7.9) << name;
    EXPECT_LT(zmax, 80.5) << name;
  }
}

TEST(TexturedSim, TubeSpansTheIssuesDepthRange) {
  const cv::Mat depth = test::textured_renderer(false).truth_depth(sim::textured_preset("tube")->surface);
  double zmin = 1e9, zmax = 0;
  for (int v = 0; v < 250; ++v)
    for (int u = 0; u < 250; ++u)
      if (const double z = depth.at<double>(v, u); !std::isnan(z)) {
        zmin = std::min(zmin, z);
        zmax = std::max(zmax, z);
      }
  EXPECT_LT(zmin, 10.0);
  EXPECT_GT(zmax, 70.0);
}

TEST(TexturedSim, RenderIsTexturedAndDarkBeyondTheFold) {
  const auto& p = test::textured_pair("plane", false);
  const auto& rig = test::paper_d3();
  // Beyond the left fold: black level plus noise (48 DN +- read and shot noise).
  double dark = 0, lit_sum = 0, lit_sq = 0;
  int nd = 0, nl = 0;
  for (int v = 1; v < 249; ++v)
    for (int u = 0; u < 249; ++u) {
      const double val = p.left.at<std::uint16_t>(v, u);
      if (!rig.left.undistort(Eigen::Vector2d(u, v)).ok()) {
        dark += val;
        ++nd;
      } else if (!std::isnan(p.depth.at<double>(v, u))) {
        lit_sum += val;
        lit_sq += val * val;
        ++nl;
      }
    }
  ASSERT_GT(nd, 1000);
  EXPECT_LT(dark / nd, 60.0);
  const double mean = lit_sum / nl, sd = std::sqrt(lit_sq / nl - mean * mean);
  EXPECT_GT(mean, 150.0);
  EXPECT_GT(sd, 40.0);  // texture contrast well above the noise (~5 DN)
}

// The benchmarks' numbered renders (bench_scene, bench_scene_limits and the tests quoting them):
// another number, another texture (not only other noise); an unknown name, an error.
TEST(TexturedSim, NumberedRendersDifferByNumberAndRefuseUnknownNames) {
  const auto& renderer = test::textured_renderer(false);
  const sim::TexturedPair a = sim::numbered_render(renderer, "height", 1);
  const sim::TexturedPair c = sim::numbered_render(renderer, "height", 2);
  // The noise alone differs by ~5 DN; another texture by its contrast (~50 DN sd).
  cv::Mat diff;
  cv::absdiff(a.left, c.left, diff);
  EXPECT_GT(cv::mean(diff)[0], 20.0);
  EXPECT_THROW(sim::numbered_render(renderer, "cube", 0), std::invalid_argument);
}

}  // namespace
}  // namespace naneye
