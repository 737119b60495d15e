// The paper's synthetic comparison (Dias et al., ICDSC 2016, "Distortion Models: Comparison"):
// six 3D points 2.189 mm apart, projected with the Dataset 3 model and pose, reconstructed with
// undistort + triangulate. The paper's baseline (a numeric inversion of the distortion, then
// triangulation) reported P 0.256 mm, D 0.628 mm, R 0.863 px; an exact inverse gives zero.
#include <gtest/gtest.h>

#include <cstdio>

#include <Eigen/Geometry>
#include <filesystem>
#include <vector>

#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/recon/geometry/metrics.hpp"
#include "naneye/recon/geometry/triangulation.hpp"

namespace naneye::recon {
namespace {

TEST(PaperSynthetic, SixPointsReconstructExactlyWithEveryMethod) {
  const StereoRig rig = load_rig(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml");
  const double pitch = 2.189;
  const int rows = 2, cols = 3;
  // A 2 x 3 grid ~70 mm in front of the rig, tilted so that the depths differ.
  const Eigen::Matrix3d tilt =
      (Eigen::AngleAxisd(0.35, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  const Eigen::Vector3d origin(-2.0, -1.0, 70.0);
  std::vector<Eigen::Vector3d> truth;
  std::vector<Eigen::Vector2d> px_left, px_right;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const Eigen::Vector3d X = origin + tilt * Eigen::Vector3d(c * pitch, r * pitch, 0.0);
      truth.push_back(X);
      px_left.push_back(rig.left.project(X));
      px_right.push_back(rig.right.project(rig.R * X + rig.T));
    }
  }
  // The ground truth itself scores zero (the criteria are not vacuous: see test_metrics.cpp).
  ASSERT_NEAR(*distance_error(truth, rows, cols, pitch), 0.0, 1e-12);

  for (TriangulationMethod m : {TriangulationMethod::dlt, TriangulationMethod::midpoint,
                                TriangulationMethod::niter2, TriangulationMethod::refined}) {
    std::vector<Eigen::Vector3d> rec;
    for (std::size_t i = 0; i < truth.size(); ++i) {
      const Triangulated t = triangulate(rig, px_left[i], px_right[i], m, 0.2);
      ASSERT_TRUE(t.ok()) << to_string(m) << " " << to_string(t.status);
      rec.push_back(t.X);
    }
    const auto P = planarity_error(rec);
    const auto D = distance_error(rec, rows, cols, pitch);
    const auto R = reprojection_error(rig, rec, px_left, px_right);
    ASSERT_TRUE(P && D && R);
    EXPECT_LT(*P, 1e-6) << to_string(m);
    EXPECT_LT(*D, 1e-6) << to_string(m);
    EXPECT_LT(*R, 1e-6) << to_string(m);
    std::printf("  %-8s P %.3g mm  D %.3g mm  R %.3g px\n", to_string(m), *P, *D, *R);
  }
}

}  // namespace
}  // namespace naneye::recon
