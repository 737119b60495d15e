#pragma once
// The one-parameter division model (Fitzgibbon, CVPR 2001; Dias et al., ICDSC 2016, Eq. 7):
//   x_u = x_d / (1 + lambda r_d^2),   homogeneous form (x_d, y_d, 1 + lambda r_d^2).
// It works on "model coordinates" x = A^-1 px, where A is an affine map to pixels:
//  * image_centred(): A = [1 0 cx; 0 1 cy; 0 0 1], (cx, cy) the image centre. The paper's first variant:
//    "the center of distortion coincided with the center of the image", pixel units (lambda in px^-2).
//    With OpenCV's convention (pixel centres at integers) the centre of a 250 x 250 image is (124.5, 124.5).
//  * normalized(): A = K, the paper's "Center of Distortion" variant: the model applied after K^-1,
//    i.e. centred on the principal point, lambda dimensionless. docs/division-model.md has the details.
//
// Valid domain: r_d < 1 / sqrt(|lambda|). For lambda < 0 the denominator vanishes there (the ray
// goes to infinity, beyond it flips behind the camera); for lambda > 0 the map r_d -> r_u peaks there and
// folds back. Inside it the map is strictly increasing and has the closed-form inverse distort().

#include <Eigen/Core>
#include <optional>

namespace naneye::recon {

struct DivisionModel {
  double lambda = 0;
  Eigen::Matrix3d A = Eigen::Matrix3d::Identity();  // model coordinates -> pixels (affine)

  static DivisionModel image_centred(double lambda, int width = 250, int height = 250);
  static DivisionModel normalized(double lambda, const Eigen::Matrix3d& K);

  Eigen::Vector2d to_model(const Eigen::Vector2d& px) const;
  Eigen::Vector2d to_pixel(const Eigen::Vector2d& x) const;

  // Edge of the valid domain in model units (1 / sqrt|lambda|); empty for lambda = 0.
  std::optional<double> max_distorted_radius() const;
  bool in_domain(const Eigen::Vector2d& xd) const;

  // Eq. 7 in homogeneous form (x_d, y_d, 1 + lambda r_d^2); defined everywhere, meaningful in the domain.
  Eigen::Vector3d lift(const Eigen::Vector2d& xd) const;
  // Eq. 7: distorted -> undistorted (model coordinates). Empty outside the domain.
  std::optional<Eigen::Vector2d> undistort(const Eigen::Vector2d& xd) const;
  // The inverse of Eq. 7: r_d solves r_u lambda r_d^2 - r_d + r_u = 0; the root kept is the one that
  // tends to r_u as lambda -> 0, r_d = 2 r_u / (1 + sqrt(1 - 4 lambda r_u^2)) (no cancellation). Empty
  // when there is no real root (lambda > 0 and r_u > 1 / (2 sqrt lambda)).
  std::optional<Eigen::Vector2d> distort(const Eigen::Vector2d& xu) const;

  // The same in pixels: raw pixel -> undistorted pixel (A x_u) and back.
  std::optional<Eigen::Vector2d> undistort_pixel(const Eigen::Vector2d& px) const;
  std::optional<Eigen::Vector2d> distort_pixel(const Eigen::Vector2d& px_u) const;
};

// The radius map of distort() alone: r_d for r_u >= 0, empty with no real root.
std::optional<double> division_distort_radius(double lambda, double r_u);

}  // namespace naneye::recon
