#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "naneye/daemon/depth_at.hpp"
#include "naneye/recon/camera/calibration_io.hpp"

using namespace naneye;

namespace {

constexpr double kSquare = 2.5;  // mm

struct Scene {
  recon::StereoRig rig =
      recon::load_rig(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml");
  Eigen::Matrix3d R = (Eigen::AngleAxisd(0.25, Eigen::Vector3d(0.3, 1, 0).normalized())).toRotationMatrix();
  Eigen::Vector3d t{-8.0, -5.5, 68.0};
  recon::PairResult result;

  Scene() {
    result.board_found = true;
    result.point_count = 48;
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 8; ++c) {
        auto& p = result.points[static_cast<std::size_t>(r * 8 + c)];
        p.id = r * 8 + c, p.row = r, p.col = c, p.valid = true;
        p.xyz_board_mm = on_board(c * kSquare, r * kSquare);
        p.xyz_mm = p.xyz_board_mm;
        p.left_px = rig.left.project(p.xyz_board_mm);
        p.depth_sigma_mm = 0.4;
      }
    recon::BoardResult b;
    b.rotation = R;
    b.translation_mm = t;
    b.normal = -R.col(2);
    b.distance_mm = std::abs(b.normal.dot(t));
    result.board = b;
  }
  Eigen::Vector3d on_board(double x, double y) const { return R * Eigen::Vector3d(x, y, 0) + t; }
};

}  // namespace

TEST(DepthAt, IntersectsTheExactRayWithTheBoardPlane) {
  Scene s;
  for (const auto& q :
       {Eigen::Vector2d(7.3, 4.1), Eigen::Vector2d(-1.5, 12.0), Eigen::Vector2d(19.0, -2.0)}) {
    const Eigen::Vector3d X = s.on_board(q.x(), q.y());
    const Eigen::Vector2d px = s.rig.left.project(X);
    const auto d = daemon::depth_at(s.rig.left, s.result, px);
    ASSERT_EQ(d.status, daemon::DepthAtStatus::ok) << daemon::to_string(d.status);
    EXPECT_NEAR((d.xyz_mm - X).norm(), 0.0, 1e-6);
    EXPECT_NEAR(d.depth_mm, X.z(), 1e-6);
    EXPECT_NEAR(d.range_mm, X.norm(), 1e-6);
    EXPECT_NEAR((d.board_xy_mm - q).norm(), 0.0, 1e-6);
    // 48 corners at 0.4 mm: the plane's offset is known to 0.4 / sqrt(48), seen along this ray.
    const Eigen::Vector3d dir = X / X.z();
    const double expected = 0.4 / std::sqrt(48.0) / std::abs(s.result.board->normal.dot(dir));
    EXPECT_NEAR(d.depth_sigma_mm, expected, 1e-9);
  }
}

TEST(DepthAt, RefusesPixelsOffTheBoardOrOutsideTheModel) {
  Scene s;
  // More than one square beyond the outer corners.
  const auto off = daemon::depth_at(s.rig.left, s.result, s.rig.left.project(s.on_board(-4.0, 5.0)));
  EXPECT_EQ(off.status, daemon::DepthAtStatus::off_board);
  const auto off2 =
      daemon::depth_at(s.rig.left, s.result, s.rig.left.project(s.on_board(8.0, 6 * kSquare + 0.5)));
  EXPECT_EQ(off2.status, daemon::DepthAtStatus::off_board);
  // Beyond the fold of the distortion model.
  ASSERT_TRUE(s.rig.left.fold_radius_px().has_value());
  const Eigen::Vector2d far(s.rig.left.cx() + 1.5 * *s.rig.left.fold_radius_px(), s.rig.left.cy());
  EXPECT_EQ(daemon::depth_at(s.rig.left, s.result, far).status, daemon::DepthAtStatus::outside_model);
  // No board in the result.
  s.result.board_found = false;
  s.result.board.reset();
  EXPECT_EQ(daemon::depth_at(s.rig.left, s.result, {125, 125}).status, daemon::DepthAtStatus::no_board);
}
