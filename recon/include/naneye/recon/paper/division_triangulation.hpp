#pragma once
// Reconstruction with a division-model rig, the two ways the paper compares:
//  * triangulate_distorted(): directly with the distorted points (paper Sec. "Center of Distortion",
//    Eq. 10): alpha1 x'_d = alpha2 R x_d + T with x_d = (x_d, y_d, 1 + lambda r_d^2) (Eq. 7's homogeneous
//    form, carried to the camera frame by K^-1 A for the image-centre variant). Multiplying on the left by
//    [x'_d]x removes alpha1: alpha2 [x'_d]x R x_d + [x'_d]x T = 0, three equations per point, linear in
//    alpha2. The left point is X = alpha2 x_d (so its depth is alpha2 (1 + lambda r_d^2)).
//  * triangulate_undistorted(): undistort with Eq. 7, then any triangulation of triangulation.hpp on
//    the pinhole rig (the paper's "division model with triangulation").
// Noise-free, both give the exact point; per point, the direct solve equals the same linear solve on the
// undistorted points even with noise, because scaling x_d or x'_d rescales the equations uniformly.

#include <Eigen/Core>
#include <span>
#include <vector>

#include "naneye/recon/geometry/triangulation.hpp"
#include "naneye/recon/paper/division_rig.hpp"

namespace naneye::recon {

enum class DirectSolve {
  per_point,  // least squares for each alpha2 alone: alpha2 = -(a . b) / (a . a), a = [x']x R x, b = [x']x T
  one_svd  // the paper's reading: one homogeneous system in (alpha2_1 .. alpha2_N, 1), one SVD (3N x (N+1))
};

const char* to_string(DirectSolve s);

struct DirectTriangulation {
  std::vector<Eigen::Vector3d> points;  // left frame, mm; NaN where !valid
  std::vector<double> alpha2;           // Eq. 10's alpha2 (NaN where !valid)
  std::vector<bool> valid;              // both pixels in the models' domains, point in front of both cameras
  bool ok = false;                      // the system could be solved at all
};

DirectTriangulation triangulate_distorted(const DivisionRig& rig, std::span<const Eigen::Vector2d> px_left,
                                          std::span<const Eigen::Vector2d> px_right, DirectSolve solve);

// Undistort both pixels with Eq. 7, then triangulate on rig.pinhole() with `method` (refined: in the
// undistorted pinhole images). A pixel outside its model's domain gives left/right_pixel_invalid.
Triangulated triangulate_undistorted(const DivisionRig& rig, const Eigen::Vector2d& px_left,
                                     const Eigen::Vector2d& px_right, TriangulationMethod method,
                                     double corner_sigma_px = 0.2);
// The same for many pairs (builds the pinhole rig once).
std::vector<Triangulated> triangulate_undistorted(const DivisionRig& rig,
                                                  std::span<const Eigen::Vector2d> px_left,
                                                  std::span<const Eigen::Vector2d> px_right,
                                                  TriangulationMethod method, double corner_sigma_px = 0.2);
// Their points, NaN where refused (for metrics.hpp).
std::vector<Eigen::Vector3d> triangulated_points(std::span<const Triangulated> t);

// R for a division rig: mean over valid points and both images of |project(X) - measured raw pixel|,
// projecting with the rig's own division models. Empty when nothing valid is left.
std::optional<double> division_reprojection_error(const DivisionRig& rig,
                                                  std::span<const Eigen::Vector3d> points,
                                                  std::span<const Eigen::Vector2d> px_left,
                                                  std::span<const Eigen::Vector2d> px_right);

}  // namespace naneye::recon
