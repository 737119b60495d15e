#pragma once
// A stereo rig whose cameras carry one-parameter division models (paper Sec. 2.1.2) instead of the
// polynomial: each camera keeps the pinhole K of the calibration and the pose X_right = R X_left + T (mm),
// and its distortion is one lambda, applied either around the image centre in pixels or on normalized
// coordinates (DivisionModel). The paper's division experiments take K, R, T from the Bouguet calibration
// and only replace the distortion; so does this.

#include <Eigen/Core>
#include <optional>

#include "naneye/recon/camera/rig.hpp"
#include "naneye/recon/paper/division_model.hpp"

namespace naneye::recon {

enum class DivisionVariant {
  image_centre,  // pixel coordinates about the image centre (the paper's first variant)
  normalized     // after K^-1, centred on the principal point (the paper's "Center of Distortion")
};

const char* to_string(DivisionVariant v);

struct DivisionCamera {
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  DivisionModel model;

  // The camera-frame ray of a raw pixel, K^-1 A (x_d, y_d, 1 + lambda r_d^2): Eq. 7's homogeneous form
  // carried to the camera frame. Not normalised; for the normalized variant (A = K) it is Eq. 7 itself.
  Eigen::Vector3d ray(const Eigen::Vector2d& px) const;
  // Raw pixel -> undistorted pixel of the pinhole K, and -> normalized coordinates. Empty outside the domain.
  std::optional<Eigen::Vector2d> undistort_pixel(const Eigen::Vector2d& px) const;
  std::optional<Eigen::Vector2d> normalized(const Eigen::Vector2d& px) const;
  // A camera-frame point (Z > 0) -> raw pixel through K and the inverse of Eq. 7. Empty when the point
  // is behind the camera or has no distorted image.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& X) const;
  bool in_domain(const Eigen::Vector2d& px) const { return model.in_domain(model.to_model(px)); }
};

struct DivisionRig {
  DivisionCamera left, right;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d T = Eigen::Vector3d::Zero();

  // The same rig with distortion-free cameras: the pinhole geometry that undistorted points live in.
  StereoRig pinhole() const;
};

// K, R, T of `rig`, distortion replaced by lambdas of the given variant (units: px^-2 for image_centre,
// dimensionless for normalized).
DivisionRig make_division_rig(const StereoRig& rig, DivisionVariant variant, double lambda_left,
                              double lambda_right);

// The model coordinates of a raw pixel for a camera of `rig` under `variant` (what the homography solver
// takes): pixel minus the image centre, or K^-1 pixel.
DivisionModel division_frame(const CameraModel& cam, DivisionVariant variant, double lambda = 0);

}  // namespace naneye::recon
