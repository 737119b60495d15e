#pragma once
// The stereo rig: two cameras and the pose X_right = R X_left + T (millimetres). The left camera's
// frame is the world frame (paper Sec. 2). See docs/camera-model.md for the conversion from the
// paper's "Relative pose" table.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>

#include "naneye/recon/camera/camera_model.hpp"

namespace naneye::recon {

// The calibration's parameters in the order of its covariance (the YAML's `calibration_covariance`):
// per eye (left, then right) fx, fy, cx, cy, k1, k2, p1, p2, k3 (K's skew is not a parameter), then
// the Rodrigues vector om of R and T (mm). A fixed parameter has zero rows and columns.
inline constexpr int kCalibrationParameters = 24;
inline constexpr int kCalibrationLeft = 0, kCalibrationRight = 9, kCalibrationOm = 18, kCalibrationT = 21;
using CalibrationCovariance = Eigen::Matrix<double, kCalibrationParameters, kCalibrationParameters>;

// One-sigma uncertainties that a calibration may carry (the *_sigma entries of the YAML file) and,
// from naneye's own calibration, the full covariance they are the marginals of: the distortion
// terms and the focal lengths are strongly correlated, so what the calibration allows a point
// (geometry/calibration_uncertainty.hpp) needs the full matrix, not the sigmas alone.
struct CalibrationSigmas {
  std::optional<Eigen::Matrix3d> M1, M2;  // per entry of K
  std::optional<Eigen::Matrix<double, 5, 1>> D1, D2;
  std::optional<Eigen::Vector3d> om;  // Rodrigues vector of R
  std::optional<Eigen::Vector3d> T;
  std::optional<CalibrationCovariance> covariance;
  // >= 1: the factor the covariance's sigmas understate the calibration's errors by, measured when
  // it was made (`naneye calibrate --cross-validate`: three halvings' depths differ by more than
  // their combined sigmas allow; docs/calibration.md). CalibrationUncertainty::of scales
  // by it; the covariance itself stays the bundle's. 1 when not measured or not beyond chance.
  double covariance_scale = 1.0;
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
