#pragma once
// What the calibration's own uncertainty allows a triangulated point: a second, systematic sigma
// beside the match's. The pixels are what they are; a calibration a little off moves the point
// that best fits them. First order (the implicit-function theorem on the triangulation's normal
// equations, J_X^T r(X, p) = 0, at r ~ 0):
//   dX/dp = -(J_X^T J_X)^-1 J_X^T J_p,   Sigma_X = (dX/dp) Sigma_p (dX/dp)^T,
// J_X = reprojection_jacobian (4 x 3), J_p the raw pixels' derivative (4 x 24) with respect to the
// calibration's parameters (rig.hpp's order), Sigma_p its covariance (mrcal's "projection
// uncertainty", here for a stereo point; Hartley & Zisserman 2nd ed. Sec. 5.2.2 for the
// propagation). Unlike the match's sigma it is common to every point of a pair (one calibration
// for all), so it does not shrink when points are averaged.

#include <Eigen/Core>
#include <array>
#include <optional>

#include "naneye/recon/camera/rig.hpp"

namespace naneye::recon {

class CalibrationUncertainty {
 public:
  // Where Sigma_p comes from: the full covariance naneye's calibration writes, or the *_sigma
  // entries alone (the paper's tables) taken as independent, the absent ones (the paper gives none
  // for om) as exact.
  enum class Basis { full_covariance, independent_sigmas };

  // From the rig's full covariance; empty without one. Only this basis gives a sigma to stand
  // behind: the marginals hide the correlations that matter most here (each eye's principal point
  // against the pose's rotation moves the disparity), and taken as independent the paper's sigmas
  // claim 9.7 % of depth at 20 mm on the axis (docs/calibration.md, "The covariance, and the depth
  // sigma it allows": over repeated calibrations they overstate the spread 3x). Scaled by the
  // rig's covariance_scale (its cross-validation at calibration; 1 when not measured).
  static std::optional<CalibrationUncertainty> of(const StereoRig& rig);
  // The *_sigma entries taken as independent: a what-if for comparisons (`naneye calib info`, the
  // tests), never a point's sigma. Empty when the rig carries no sigma at all.
  static std::optional<CalibrationUncertainty> assuming_independent_sigmas(const StereoRig& rig);

  Basis basis() const { return basis_; }
  const CalibrationCovariance& covariance() const { return cov_; }

  // Sigma_X (mm^2, left frame) for the point X (left frame, mm) triangulated from the pixels it
  // projects to.
  Eigen::Matrix3d point_covariance(const Eigen::Vector3d& X) const;
  // sqrt of its (2, 2) entry: the one-sigma depth the calibration allows, mm.
  double depth_sigma_mm(const Eigen::Vector3d& X) const;

  // d(pixels)/d(parameters) at X: rows left u, v, right u, v (4 x 24). Public for its test against
  // finite differences of CameraModel::project.
  Eigen::Matrix<double, 4, kCalibrationParameters> parameter_jacobian(const Eigen::Vector3d& X) const;

 private:
  CalibrationUncertainty(const StereoRig& rig, const CalibrationCovariance& cov, Basis basis);
  StereoRig rig_;
  CalibrationCovariance cov_;
  Basis basis_;
  std::array<Eigen::Matrix3d, 3> dR_dom_;  // dR/d(om_k), by central differences of Rodrigues
};

}  // namespace naneye::recon
