#pragma once
// Triangulation of a corresponding pair of raw (distorted) pixels with a StereoRig
// (X_right = R X_left + T, mm; the left camera's frame is the world frame).
//
// Methods:
//  - dlt:      linear DLT on normalized coordinates, P1 = [I|0], P2 = [R|T] (the paper's baseline,
//              Hartley & Zisserman 2nd ed. Sec. 12.2).
//  - midpoint: midpoint of the closest points of the two rays (H&Z Sec. 12.5 / Beardsley et al.).
//  - niter2:   Lindstrom's optimal correction ("Triangulation made easy", CVPR 2010, listing niter2)
//              of the normalized points onto the epipolar constraint, then the (now exact) intersection.
//  - refined:  niter2, then Gauss-Newton on the raw-pixel reprojection error in both images: the
//              maximum-likelihood point for isotropic pixel noise, which matters at the image edges
//              where the distortion makes normalized-plane errors a poor proxy for pixel errors.
//
// Every accepted point carries a depth sigma from first-order propagation of the corner sigma
// (see point_covariance()).

#include <Eigen/Core>
#include <limits>

#include "naneye/recon/camera/camera_model.hpp"
#include "naneye/recon/camera/rig.hpp"

namespace naneye::recon {

enum class TriangulationMethod { dlt, midpoint, niter2, refined };

const char* to_string(TriangulationMethod m);

enum class TriangulationStatus {
  ok,
  left_pixel_invalid,   // undistort() of the left pixel failed; see Triangulated::left_undistort
  right_pixel_invalid,  // same for the right pixel (left_pixel_invalid wins when both fail)
  parallel_rays,        // the rays do not meet at a finite point (DLT: w = 0; midpoint: parallel)
  behind_camera,        // the intersection lies behind one of the cameras (Z <= 0)
};

const char* to_string(TriangulationStatus s);

struct Triangulated {
  TriangulationStatus status = TriangulationStatus::parallel_rays;
  // Why a pixel was refused (UndistortStatus::outside_model beyond the fold of the model); both
  // sides are always filled in by the pixel-level triangulate().
  UndistortStatus left_undistort = UndistortStatus::ok;
  UndistortStatus right_undistort = UndistortStatus::ok;
  // Left (world) frame, mm. NaN unless ok(): a refused pair never yields a number.
  Eigen::Vector3d X = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  // One sigma of X.z() (mm) from the corner sigma; NaN unless ok().
  double depth_sigma_mm = std::numeric_limits<double>::quiet_NaN();
  bool ok() const { return status == TriangulationStatus::ok; }
};

// One observation after undistortion: raw pixels (needed by the refinement and the covariance)
// and their normalized (undistorted) coordinates, so that batch callers undistort only once.
struct StereoObservation {
  Eigen::Vector2d px_left, px_right;  // raw pixels
  Eigen::Vector2d xn_left, xn_right;  // CameraModel::undistort(px).normalized
};

// The top level: undistorts both pixels (refusing pixels outside a camera's model domain), then
// triangulates. corner_sigma_px is the one-sigma corner error in each image, for depth_sigma_mm.
Triangulated triangulate(const StereoRig& rig, const Eigen::Vector2d& px_left,
                         const Eigen::Vector2d& px_right, TriangulationMethod method, double corner_sigma_px);

// Same, from an already undistorted observation.
Triangulated triangulate(const StereoRig& rig, const StereoObservation& obs, TriangulationMethod method,
                         double corner_sigma_px);

// --- The building blocks, on normalized coordinates (no validity checks; the caller checks). ---

// Linear DLT: the right singular vector of the 4x4 system; w may be ~0 for parallel rays (then the
// result is not finite).
Eigen::Vector3d triangulate_dlt(const StereoRig& rig, const Eigen::Vector2d& xl, const Eigen::Vector2d& xr);

// Midpoint of the shortest segment between the rays; not finite for parallel rays.
Eigen::Vector3d triangulate_midpoint(const StereoRig& rig, const Eigen::Vector2d& xl,
                                     const Eigen::Vector2d& xr);

struct CorrectedPair {
  Eigen::Vector2d xl, xr;
};

// Lindstrom's niter2: two closed-form update steps towards the pair closest (L2 on the normalized
// image planes) to (xl, xr) that satisfies xr^T E xl = 0, with E = rig.essential() = [T]x R.
// Its cost matches a brute-force optimum to ~1e-9 relative (tests/geometry/test_triangulation.cpp).
CorrectedPair niter2_correct(const Eigen::Matrix3d& E, const Eigen::Vector2d& xl, const Eigen::Vector2d& xr);

// The intersection of two rays that satisfy the epipolar constraint: X = z (xl, 1) with z solving
// xr x (R z xl + T) = 0 in least squares.
Eigen::Vector3d intersect_corrected(const StereoRig& rig, const CorrectedPair& c);

// niter2_correct + intersect_corrected.
Eigen::Vector3d triangulate_niter2(const StereoRig& rig, const Eigen::Vector2d& xl,
                                   const Eigen::Vector2d& xr);

// Gauss-Newton on the raw-pixel reprojection error in both images from X0 (damped like
// Levenberg-Marquardt only when a full step would raise the cost); stops when the step is below
// 1e-12 of |X| or the cost stops decreasing. Never returns a point with a higher cost than X0.
Eigen::Vector3d refine_reprojection(const StereoRig& rig, const Eigen::Vector3d& X0,
                                    const Eigen::Vector2d& px_left, const Eigen::Vector2d& px_right,
                                    int max_iterations = 10);

// Stacked raw-pixel residuals [project_left(X) - px_left; project_right(R X + T) - px_right].
Eigen::Vector4d reprojection_residual(const StereoRig& rig, const Eigen::Vector3d& X,
                                      const Eigen::Vector2d& px_left, const Eigen::Vector2d& px_right);

// d(residual)/dX, analytic: per camera K2x2 * distort_jacobian(x/z) * d(x/z)/dX (times R on the right).
Eigen::Matrix<double, 4, 3> reprojection_jacobian(const StereoRig& rig, const Eigen::Vector3d& X);

// First-order covariance of X (Hartley & Zisserman 2nd ed. Sec. 5.2, Result 5.10 for an
// over-determined ML estimate): Sigma_X = sigma_px^2 (J^T J)^-1, J = reprojection_jacobian(X),
// assuming independent isotropic corner noise of sigma_px in each of the four pixel coordinates.
Eigen::Matrix3d point_covariance(const StereoRig& rig, const Eigen::Vector3d& X, double corner_sigma_px);

// sqrt(Sigma_X(2, 2)): the one-sigma depth (Z in the left frame).
double depth_sigma_mm(const StereoRig& rig, const Eigen::Vector3d& X, double corner_sigma_px);

}  // namespace naneye::recon
