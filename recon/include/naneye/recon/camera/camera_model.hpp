#pragma once
// The camera model of docs/camera-model.md: pinhole K and OpenCV's 5-coefficient "plumb_bob"
// distortion (k1, k2, p1, p2, k3), the paper's polynomial model (Dias et al., ICDSC 2016, Eq. 3-6;
// its calibrations use p1 = p2 = 0).
//
// Coordinates: "normalized" = X/Z, Y/Z on the undistorted image plane (paper Eq. 4); "distorted" =
// the normalized point after Eq. 5; "pixel" = K applied to the distorted point (Eq. 6), pixel centres
// at integer coordinates as in OpenCV.

#include <Eigen/Core>
#include <optional>

namespace naneye::recon {

struct Distortion {
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
  bool has_tangential() const { return p1 != 0.0 || p2 != 0.0; }
  // OpenCV's order (k1, k2, p1, p2, k3): the distCoeffs of calib3d and of calibration files.
  Eigen::Matrix<double, 1, 5> opencv_order() const { return {k1, k2, p1, p2, k3}; }
};

enum class UndistortStatus {
  ok,
  outside_model,  // beyond the fold of the distortion model: no undistorted point maps here
  no_convergence  // only possible with tangential terms near the domain edge; never returned as a number
};

const char* to_string(UndistortStatus s);

struct Undistorted {
  UndistortStatus status = UndistortStatus::outside_model;
  Eigen::Vector2d normalized{0, 0};  // valid only when status == ok
  int iterations = 0;
  bool ok() const { return status == UndistortStatus::ok; }
};

class CameraModel {
 public:
  CameraModel() = default;
  CameraModel(const Eigen::Matrix3d& K, const Distortion& d, int width = 250, int height = 250);

  const Eigen::Matrix3d& K() const { return K_; }
  const Distortion& distortion() const { return d_; }
  int width() const { return width_; }
  int height() const { return height_; }
  double fx() const { return K_(0, 0); }
  double fy() const { return K_(1, 1); }
  double cx() const { return K_(0, 2); }
  double cy() const { return K_(1, 2); }
  double skew() const { return K_(0, 1); }

  // Paper Eq. 5 (plus OpenCV's tangential terms): normalized -> distorted normalized.
  Eigen::Vector2d distort(const Eigen::Vector2d& xn) const;
  // d(distort)/d(xn), analytic.
  Eigen::Matrix2d distort_jacobian(const Eigen::Vector2d& xn) const;
  // Paper Eq. 6: distorted normalized -> pixel, and its inverse.
  Eigen::Vector2d to_pixel(const Eigen::Vector2d& xd) const;
  Eigen::Vector2d from_pixel(const Eigen::Vector2d& px) const;
  // Paper Eq. 3-6: a 3D point in this camera's frame (Z > 0) -> raw pixel.
  Eigen::Vector2d project(const Eigen::Vector3d& X) const;
  // project() of the n points r_i z + t (the rays r_i, given as planes x, y, z, at one depth z, moved
  // by t): the same bits as project(r_i * z + t) point by point, two points per SSE2 operation for
  // the radial-only model (the scene paths' window shapes: ~170 points per feature).
  void project_rays_at(const double* rx, const double* ry, const double* rz, double z,
                       const Eigen::Vector3d& t, int n, Eigen::Vector2d* out) const;
  // project() and its 2x3 Jacobian d(pixel)/dX: K(2x2) * distort_jacobian * d(X/Z, Y/Z)/dX.
  Eigen::Vector2d project(const Eigen::Vector3d& X, Eigen::Matrix<double, 2, 3>& J) const;
  // Raw pixel -> normalized, the exact inverse of distort(): Newton with the analytic Jacobian.
  // A pixel beyond the fold returns outside_model, never a number.
  Undistorted undistort(const Eigen::Vector2d& px) const;
  Undistorted undistort_distorted(const Eigen::Vector2d& xd) const;

  // The valid domain (docs/camera-model.md): the radius (normalized, undistorted) where the radial
  // map r -> r (1 + k1 r^2 + k2 r^4 + k3 r^6) stops increasing, and its image radius r_d.
  // Empty when the model never folds. With tangential terms the domain is checked per point.
  std::optional<double> fold_radius_undistorted() const { return fold_r_; }
  std::optional<double> fold_radius_distorted() const { return fold_rd_; }
  // The fold in pixels along the x axis (r_d * fx), as `naneye calib info` reports it.
  std::optional<double> fold_radius_px() const;
  // True when the raw pixel lies inside the domain (undistort would succeed).
  bool in_domain(const Eigen::Vector2d& px) const { return undistort(px).ok(); }

 private:
  Undistorted undistort_radial(const Eigen::Vector2d& xd) const;
  Undistorted undistort_general(const Eigen::Vector2d& xd) const;
  bool inside_fold_general(const Eigen::Vector2d& xn) const;

  Eigen::Matrix3d K_ = Eigen::Matrix3d::Identity();
  Distortion d_;
  int width_ = 250, height_ = 250;
  std::optional<double> fold_r_, fold_rd_;
};

// distort, to_pixel and project are defined here so that the hot loops of the scene paths (~250 000
// projections per pair) inline them: a call each cost as much again as the arithmetic.
inline Eigen::Vector2d CameraModel::distort(const Eigen::Vector2d& xn) const {
  const double x = xn.x(), y = xn.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (d_.k1 + r2 * (d_.k2 + r2 * d_.k3));
  // The paper's model is radial only (p1 = p2 = 0): the tangential terms would add exact zeros, so
  // the short form gives the same bits (up to a zero's sign) for half the work.
  if (!d_.has_tangential()) return {x * radial, y * radial};
  return {x * radial + 2.0 * d_.p1 * x * y + d_.p2 * (r2 + 2.0 * x * x),
          y * radial + d_.p1 * (r2 + 2.0 * y * y) + 2.0 * d_.p2 * x * y};
}

inline Eigen::Vector2d CameraModel::to_pixel(const Eigen::Vector2d& xd) const {
  return {fx() * xd.x() + skew() * xd.y() + cx(), fy() * xd.y() + cy()};
}

inline Eigen::Vector2d CameraModel::project(const Eigen::Vector3d& X) const {
  return to_pixel(distort(X.head<2>() / X.z()));
}

// Smallest positive radius where d/dr [r (1 + k1 r^2 + k2 r^4 + k3 r^6)] = 0, i.e. the smallest
// positive root s = r^2 of 7 k3 s^3 + 5 k2 s^2 + 3 k1 s + 1 = 0. Empty when there is none.
std::optional<double> radial_fold_radius(double k1, double k2, double k3);

}  // namespace naneye::recon
