#pragma once
// The pose of a known planar board from both eyes at once. With a ~1 mm baseline, per-corner
// triangulation fixes depth only to millimetres at 70 mm (paper Eq. 2: dZ = Z^2 / (f T) dd); a board of
// known geometry seen by both cameras constrains depth through its apparent size as well, which is an
// order of magnitude better. This answers the paper's closing remark on depth from a small baseline.
#include <Eigen/Core>
#include <span>

#include "naneye/recon/camera/rig.hpp"
#include "naneye/recon/geometry/board.hpp"

namespace naneye::recon {

// One corner seen by one or both eyes (raw pixels); a side with `*_ok` false is not used.
struct CornerObservation {
  int row = 0, col = 0;
  Eigen::Vector2d left_px{0, 0}, right_px{0, 0};
  bool left_ok = false, right_ok = false;
};

struct BoardPose {
  bool ok = false;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // board -> left camera
  Eigen::Vector3d t = Eigen::Vector3d::Zero();      // mm
  double rms_px = 0;                                // raw-pixel reprojection RMS over every residual used
  int residuals = 0;                                // 2 per observation and eye
  int iterations = 0;
  // First-order covariance of (d_omega, d_t), d_omega a left-multiplied rotation increment:
  // sigma_px^2 (J^T J)^-1 (Hartley & Zisserman, 2nd ed., Sec. 5.2.2).
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();

  Eigen::Vector3d normal() const;    // unit board normal in the left frame, pointing to the camera
  double plane_distance_mm() const;  // distance of the board plane from the left camera centre
  Eigen::Vector3d to_camera(const Eigen::Vector3d& board_point) const { return R * board_point + t; }
};

// Gauss-Newton on the raw-pixel reprojection error in both cameras (6 DoF), initialised by a planar
// PnP (IPPE) on the exactly undistorted left (or right) points. Needs >= 4 observations seen by one
// eye; returns ok = false otherwise or when the optimisation diverges.
BoardPose estimate_board_pose(const StereoRig& rig, const BoardGeometry& board,
                              std::span<const CornerObservation> obs, double corner_sigma_px);

// Depth (Z in the left frame) where the left raw pixel's exact ray meets the board plane, with its
// first-order sigma from the pose covariance. Empty when the pixel is outside the model's domain or the
// ray does not hit the plane in front of the camera.
struct RayHit {
  Eigen::Vector3d point{0, 0, 0};
  double depth_mm = 0, depth_sigma_mm = 0;
};
std::optional<RayHit> intersect_board(const StereoRig& rig, const BoardPose& pose,
                                      const Eigen::Vector2d& left_px);

}  // namespace naneye::recon
