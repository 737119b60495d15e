#pragma once
// The stereo rig: two cameras and the pose X_right = R X_left + T (millimetres). The left camera's
// frame is the world frame (paper Sec. 2). See docs/camera-model.md for the conversion from the
// paper's "Relative pose" table.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>

#include "naneye/recon/camera/camera_model.hpp"

namespace naneye::recon {

// One-sigma uncertainties that a calibration may carry (the *_sigma entries of the YAML file).
struct CalibrationSigmas {
  std::optional<Eigen::Matrix3d> M1, M2;  // per entry of K
  std::optional<Eigen::Matrix<double, 5, 1>> D1, D2;
  std::optional<Eigen::Vector3d> om;  // Rodrigues vector of R
  std::optional<Eigen::Vector3d> T;
};

struct StereoRig {
  CameraModel left, right;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // X_right = R X_left + T
  Eigen::Vector3d T = Eigen::Vector3d::Zero();      // mm
  CalibrationSigmas sigmas;

  // The right camera's optical centre in the left (world) frame: C = -R^T T.
  Eigen::Vector3d right_center() const { return -R.transpose() * T; }
  double baseline_mm() const { return T.norm(); }
  double rotation_angle_rad() const { return Eigen::AngleAxisd(R).angle(); }
  // Essential matrix E = [T]x R, so that xr^T E xl = 0 for normalized homogeneous points.
  Eigen::Matrix3d essential() const;
};

// Rodrigues vector <-> rotation matrix (the paper's omega; OpenCV's cv::Rodrigues convention).
Eigen::Matrix3d rodrigues(const Eigen::Vector3d& om);
Eigen::Vector3d rodrigues(const Eigen::Matrix3d& R);
Eigen::Matrix3d skew(const Eigen::Vector3d& v);

}  // namespace naneye::recon
