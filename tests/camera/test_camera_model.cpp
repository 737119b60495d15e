// The camera model: distort/project as the paper's Eq. 3-6, undistort as their exact inverse inside
// the valid domain, a clear refusal beyond the fold.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/recon/camera/camera_model.hpp"
#include "naneye/recon/camera/domain_report.hpp"

using naneye::recon::CameraModel;
using naneye::recon::Distortion;
using naneye::recon::UndistortStatus;

namespace {

CameraModel paper_camera(double fx, double fy, double cx, double cy, double k1, double k2, double k3) {
  Eigen::Matrix3d K;
  K << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return CameraModel(K, Distortion{k1, k2, 0, 0, k3});
}

// The paper's three calibrations (Tables "Intrinsic parameters", left and right camera).
std::vector<std::pair<std::string, CameraModel>> paper_cameras() {
  return {
      {"d1-left", paper_camera(216.520, 216.259, 122.241, 113.410, -0.349, 0.148, 0.0)},
      {"d1-right", paper_camera(213.860, 213.325, 123.132, 124.568, -0.344, 0.143, 0.0)},
      {"d2-left", paper_camera(216.307, 216.421, 121.847, 112.981, -0.353, 0.144, 0.0)},
      {"d2-right", paper_camera(215.601, 215.412, 123.486, 122.412, -0.342, 0.124, 0.0)},
      {"d3-left", paper_camera(216.360, 216.315, 122.414, 111.535, -0.369, 0.303, -0.366)},
      {"d3-right", paper_camera(216.258, 216.379, 124.419, 122.283, -0.336, -0.103, 0.866)},
  };
}

}  // namespace

TEST(Camera, ProjectFollowsPaperEquations) {
  const CameraModel cam = paper_camera(216.36, 216.315, 122.414, 111.535, -0.369, 0.303, -0.366);
  const Eigen::Vector3d X(3.0, -2.0, 10.0);
  // Eq. 4: normalized; Eq. 5: radial factor; Eq. 6: K.
  const double xn = 0.3, yn = -0.2, r2 = xn * xn + yn * yn;
  const double f = 1 - 0.369 * r2 + 0.303 * r2 * r2 - 0.366 * r2 * r2 * r2;
  const Eigen::Vector2d px = cam.project(X);
  EXPECT_NEAR(px.x(), 216.36 * xn * f + 122.414, 1e-12);
  EXPECT_NEAR(px.y(), 216.315 * yn * f + 111.535, 1e-12);
}

TEST(Camera, TangentialTermsFollowOpenCv) {
  Eigen::Matrix3d K;
  K << 200, 0.5, 120, 0, 201, 118, 0, 0, 1;
  const CameraModel cam(K, Distortion{-0.3, 0.1, 0.002, -0.001, 0.01});
  const Eigen::Vector2d xn(0.25, -0.4);
  const double x = xn.x(), y = xn.y(), r2 = x * x + y * y;
  const double radial = 1 - 0.3 * r2 + 0.1 * r2 * r2 + 0.01 * r2 * r2 * r2;
  const double xd = x * radial + 2 * 0.002 * x * y + -0.001 * (r2 + 2 * x * x);
  const double yd = y * radial + 0.002 * (r2 + 2 * y * y) + 2 * -0.001 * x * y;
  const Eigen::Vector2d d = cam.distort(xn);
  EXPECT_NEAR(d.x(), xd, 1e-15);
  EXPECT_NEAR(d.y(), yd, 1e-15);
}

TEST(Camera, JacobianMatchesFiniteDifferences) {
  Eigen::Matrix3d K;
  K << 216, 0, 122, 0, 216, 111, 0, 0, 1;
  const CameraModel cam(K, Distortion{-0.369, 0.303, 0.003, -0.002, -0.366});
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector2d x(u(rng), u(rng));
    const Eigen::Matrix2d J = cam.distort_jacobian(x);
    const double h = 1e-6;
    for (int c = 0; c < 2; ++c) {
      Eigen::Vector2d dx = Eigen::Vector2d::Zero();
      dx[c] = h;
      const Eigen::Vector2d fd = (cam.distort(x + dx) - cam.distort(x - dx)) / (2 * h);
      EXPECT_NEAR((J.col(c) - fd).norm(), 0.0, 1e-9);
    }
  }
}

TEST(Camera, FoldOfDataset3LeftCamera) {
  // The figures: r_d(r) peaks at r = 0.855, r_d = 0.6406 (138.6 px); 11.7 % of the image
  // lies beyond it.
  const CameraModel cam = paper_camera(216.360, 216.315, 122.414, 111.535, -0.369, 0.303, -0.366);
  ASSERT_TRUE(cam.fold_radius_undistorted());
  EXPECT_NEAR(*cam.fold_radius_undistorted(), 0.855, 5e-4);
  EXPECT_NEAR(*cam.fold_radius_distorted(), 0.6406, 5e-5);
  EXPECT_NEAR(*cam.fold_radius_px(), 138.6, 0.05);
  // The derivative of r_d(r) vanishes there.
  const double r = *cam.fold_radius_undistorted(), s = r * r;
  EXPECT_NEAR(1 + 3 * -0.369 * s + 5 * 0.303 * s * s + 7 * -0.366 * s * s * s, 0.0, 1e-12);
  const auto report = naneye::recon::analyze_domain(cam);
  EXPECT_EQ(report.pixels_total, 250 * 250);
  EXPECT_NEAR(1.0 - report.valid_share(), 0.117, 0.001);
}

TEST(Camera, MonotonicModelsNeverFold) {
  for (const auto& [name, cam] : paper_cameras()) {
    if (name == "d3-left") continue;
    EXPECT_FALSE(cam.fold_radius_undistorted()) << name;
    EXPECT_EQ(naneye::recon::analyze_domain(cam).pixels_valid, 250 * 250) << name;
  }
}

// Round trip <= 1e-6 px at every pixel centre and at random sub-pixel points, for the paper's three
// datasets and both cameras.
TEST(Camera, UndistortRoundTripEveryPixelAllDatasets) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> coord(-0.5, 249.5);
  for (const auto& [name, cam] : paper_cameras()) {
    const auto report = naneye::recon::analyze_domain(cam);
    EXPECT_LE(report.max_roundtrip_error_px, 1e-6) << name;
    EXPECT_GT(report.pixels_valid, 0) << name;
    double worst = 0;
    int valid = 0;
    for (int i = 0; i < 200000; ++i) {
      const Eigen::Vector2d px(coord(rng), coord(rng));
      const auto err = naneye::recon::roundtrip_error_px(cam, px);
      if (!err) continue;
      ++valid;
      worst = std::max(worst, *err);
    }
    EXPECT_GT(valid, 150000) << name;
    EXPECT_LE(worst, 1e-6) << name;
  }
}

TEST(Camera, RoundTripRightUpToTheFold) {
  const CameraModel cam = paper_camera(216.360, 216.315, 122.414, 111.535, -0.369, 0.303, -0.366);
  const double rd_max = *cam.fold_radius_distorted();
  for (double frac : {0.9, 0.99, 0.999, 0.99999, 0.9999999}) {
    for (double angle = 0; angle < 2 * M_PI; angle += 0.3) {
      const Eigen::Vector2d xd = frac * rd_max * Eigen::Vector2d(std::cos(angle), std::sin(angle));
      const auto u = cam.undistort_distorted(xd);
      ASSERT_TRUE(u.ok()) << frac;
      EXPECT_LT(u.normalized.norm(), *cam.fold_radius_undistorted());
      const Eigen::Vector2d px = cam.to_pixel(xd);
      EXPECT_LE((cam.to_pixel(cam.distort(u.normalized)) - px).norm(), 1e-6) << frac;
    }
  }
}

TEST(Camera, BeyondTheFoldIsRefused) {
  const CameraModel cam = paper_camera(216.360, 216.315, 122.414, 111.535, -0.369, 0.303, -0.366);
  // Image corners are beyond the fold (radius ~170 px).
  for (const Eigen::Vector2d& px :
       {Eigen::Vector2d(0, 0), Eigen::Vector2d(249, 0), Eigen::Vector2d(0, 249), Eigen::Vector2d(249, 249)}) {
    const auto u = cam.undistort(px);
    EXPECT_EQ(u.status, UndistortStatus::outside_model);
    EXPECT_FALSE(cam.in_domain(px));
  }
  // Just beyond the distorted fold radius, in any direction.
  for (double angle = 0; angle < 2 * M_PI; angle += 0.1) {
    const Eigen::Vector2d xd =
        1.000001 * *cam.fold_radius_distorted() * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    EXPECT_EQ(cam.undistort_distorted(xd).status, UndistortStatus::outside_model);
  }
  // Points that the forward model maps beyond the fold come back folded: undistort never returns them.
  const Eigen::Vector2d folded = cam.distort(Eigen::Vector2d(1.0, 0.0));  // r = 1.0 > fold 0.855
  const auto u = cam.undistort_distorted(folded);
  ASSERT_TRUE(u.ok());  // r_d(1.0) < r_d max: the preimage inside the fold is the answer
  EXPECT_LT(u.normalized.norm(), 0.855);
  EXPECT_FALSE(cam.undistort(Eigen::Vector2d(NAN, 3)).ok());
}

TEST(Camera, TangentialModelRoundTripAndDomain) {
  Eigen::Matrix3d K;
  K << 216, 0, 122, 0, 216, 111, 0, 0, 1;
  const CameraModel cam(K, Distortion{-0.369, 0.303, 0.002, -0.0015, -0.366});
  int valid = 0, refused = 0;
  double worst = 0;
  for (int v = 0; v < 250; v += 2) {
    for (int u = 0; u < 250; u += 2) {
      const Eigen::Vector2d px(u, v);
      const auto und = cam.undistort(px);
      if (!und.ok()) {
        ++refused;
        continue;
      }
      ++valid;
      worst = std::max(worst, (cam.to_pixel(cam.distort(und.normalized)) - px).norm());
      EXPECT_GT(cam.distort_jacobian(und.normalized).determinant(), 0.0);
    }
  }
  EXPECT_LE(worst, 1e-6);
  EXPECT_GT(valid, 0.8 * (valid + refused));
  EXPECT_GT(refused, 0);  // the image corners lie beyond the fold
}

TEST(Camera, RadialFoldRadiusClosedCases) {
  // k1 only: 1 + 3 k1 s = 0 -> s = -1 / (3 k1).
  EXPECT_NEAR(*naneye::recon::radial_fold_radius(-0.5, 0, 0), std::sqrt(1.0 / 1.5), 1e-12);
  EXPECT_FALSE(naneye::recon::radial_fold_radius(0.1, 0.0, 0.0));
  EXPECT_FALSE(naneye::recon::radial_fold_radius(0.0, 0.0, 0.0));
}

// project_rays_at is project() on two lanes: the same bits for every point, whether it falls in a
// pair or in the odd tail, for the paper's radial models and with tangential terms (scalar path).
TEST(Camera, ProjectRaysAtGivesProjectsBits) {
  Eigen::Matrix3d K;
  K << 200, 0.5, 120, 0, 201, 118, 0, 0, 1;
  auto cams = paper_cameras();
  cams.emplace_back("tangential", CameraModel(K, Distortion{-0.3, 0.1, 0.002, -0.001, 0.01}));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ray(-0.6, 0.6), tilt(0.9, 1.1), depth(5.0, 80.0), shift(-1.0, 1.0);
  for (const auto& [name, cam] : cams)
    for (int n = 1; n <= 7; ++n) {
      double rx[7], ry[7], rz[7];
      for (int i = 0; i < n; ++i) {
        rx[i] = ray(rng);
        ry[i] = ray(rng);
        rz[i] = tilt(rng);
      }
      const double z = depth(rng);
      const Eigen::Vector3d t(shift(rng), shift(rng), shift(rng));
      Eigen::Vector2d out[7];
      cam.project_rays_at(rx, ry, rz, z, t, n, out);
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector2d want =
            cam.project(Eigen::Vector3d(rx[i] * z + t.x(), ry[i] * z + t.y(), rz[i] * z + t.z()));
        EXPECT_EQ(out[i].x(), want.x()) << name << " n " << n << " i " << i;
        EXPECT_EQ(out[i].y(), want.y()) << name << " n " << n << " i " << i;
      }
    }
}
