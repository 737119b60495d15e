#include "naneye/recon/geometry/calibration_uncertainty.hpp"

#include <Eigen/Cholesky>
#include <cmath>

#include "naneye/recon/geometry/triangulation.hpp"

namespace naneye::recon {
namespace {

// The diagonal Sigma_p from the *_sigma entries alone (absent entries: zero).
CalibrationCovariance from_sigmas(const CalibrationSigmas& s) {
  Eigen::Matrix<double, kCalibrationParameters, 1> sd =
      Eigen::Matrix<double, kCalibrationParameters, 1>::Zero();
  const auto eye = [&](int first, const std::optional<Eigen::Matrix3d>& M,
                       const std::optional<Eigen::Matrix<double, 5, 1>>& D) {
    if (M) sd.segment<4>(first) << (*M)(0, 0), (*M)(1, 1), (*M)(0, 2), (*M)(1, 2);
    if (D) sd.segment<5>(first + 4) = *D;  // k1 k2 p1 p2 k3: OpenCV's order is rig.hpp's
  };
  eye(kCalibrationLeft, s.M1, s.D1);
  eye(kCalibrationRight, s.M2, s.D2);
  if (s.om) sd.segment<3>(kCalibrationOm) = *s.om;
  if (s.T) sd.segment<3>(kCalibrationT) = *s.T;
  return sd.cwiseAbs2().asDiagonal();
}

bool any_sigma(const CalibrationSigmas& s) {
  return s.M1 || s.M2 || s.D1 || s.D2 || s.om || s.T;
}

// d(pixel)/d(fx fy cx cy k1 k2 p1 p2 k3) of `cam` at the point Xc of its own frame: the pixel is
// K (distort(x)) with x = Xc.xy / Xc.z (paper Eq. 3-6, OpenCV's tangential terms).
Eigen::Matrix<double, 2, 9> intrinsic_jacobian(const CameraModel& cam, const Eigen::Vector3d& Xc) {
  const Eigen::Vector2d xn = Xc.head<2>() / Xc.z();
  const double x = xn.x(), y = xn.y(), r2 = x * x + y * y;
  const Eigen::Vector2d xd = cam.distort(xn);
  Eigen::Matrix<double, 2, 5> dxd;  // d(distorted normalized)/d(k1 k2 p1 p2 k3)
  dxd << x * r2, x * r2 * r2, 2.0 * x * y, r2 + 2.0 * x * x, x * r2 * r2 * r2,  //
      y * r2, y * r2 * r2, r2 + 2.0 * y * y, 2.0 * x * y, y * r2 * r2 * r2;
  Eigen::Matrix2d Kd;
  Kd << cam.fx(), cam.skew(), 0.0, cam.fy();
  Eigen::Matrix<double, 2, 9> J;
  J.leftCols<4>() << xd.x(), 0.0, 1.0, 0.0, 0.0, xd.y(), 0.0, 1.0;
  J.rightCols<5>() = Kd * dxd;
  return J;
}

}  // namespace

std::optional<CalibrationUncertainty> CalibrationUncertainty::of(const StereoRig& rig) {
  if (!rig.sigmas.covariance) return std::nullopt;
  const double k = rig.sigmas.covariance_scale;
  return CalibrationUncertainty(rig, k * k * *rig.sigmas.covariance, Basis::full_covariance);
}

std::optional<CalibrationUncertainty> CalibrationUncertainty::assuming_independent_sigmas(
    const StereoRig& rig) {
  if (!any_sigma(rig.sigmas)) return std::nullopt;
  return CalibrationUncertainty(rig, from_sigmas(rig.sigmas), Basis::independent_sigmas);
}

CalibrationUncertainty::CalibrationUncertainty(const StereoRig& rig, const CalibrationCovariance& cov,
                                               Basis basis)
    : rig_(rig), cov_(cov), basis_(basis) {
  // Central differences of a closed-form map: the step's truncation (~h^2 = 1e-12) and rounding
  // (~1e-16 / h = 1e-10) both far below the parameters' relative sigmas (>= 1e-4).
  const Eigen::Vector3d om = rodrigues(rig.R);
  const double h = 1e-6;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d(k) = h;
    dR_dom_[static_cast<std::size_t>(k)] =
        (rodrigues(Eigen::Vector3d(om + d)) - rodrigues(Eigen::Vector3d(om - d))) / (2.0 * h);
  }
}

Eigen::Matrix<double, 4, kCalibrationParameters> CalibrationUncertainty::parameter_jacobian(
    const Eigen::Vector3d& X) const {
  Eigen::Matrix<double, 4, kCalibrationParameters> J =
      Eigen::Matrix<double, 4, kCalibrationParameters>::Zero();
  J.block<2, 9>(0, kCalibrationLeft) = intrinsic_jacobian(rig_.left, X);
  const Eigen::Vector3d Xr = rig_.R * X + rig_.T;
  J.block<2, 9>(2, kCalibrationRight) = intrinsic_jacobian(rig_.right, Xr);
  Eigen::Matrix<double, 2, 3> dpx_dXr;
  rig_.right.project(Xr, dpx_dXr);
  for (int k = 0; k < 3; ++k)
    J.block<2, 1>(2, kCalibrationOm + k) = dpx_dXr * (dR_dom_[static_cast<std::size_t>(k)] * X);
  J.block<2, 3>(2, kCalibrationT) = dpx_dXr;
  return J;
}

Eigen::Matrix3d CalibrationUncertainty::point_covariance(const Eigen::Vector3d& X) const {
  const Eigen::Matrix<double, 4, 3> Jx = reprojection_jacobian(rig_, X);
  // dX/dp = -(Jx^T Jx)^-1 Jx^T Jp; the sign drops out of the covariance.
  const Eigen::Matrix<double, 3, kCalibrationParameters> dX =
      (Jx.transpose() * Jx).ldlt().solve(Jx.transpose() * parameter_jacobian(X));
  return dX * cov_ * dX.transpose();
}

double CalibrationUncertainty::depth_sigma_mm(const Eigen::Vector3d& X) const {
  // point_covariance()(2, 2) with only Z's row of dX/dp: g = e_z^T (Jx^T Jx)^-1 Jx^T, then
  // (g Jp) Sigma_p (g Jp)^T, a 24-vector's quadratic form instead of the 3 x 3 product (1.17 -> 0.31 us a
  // point, bench_recon BM_CalibrationDepthSigma).
  const Eigen::Matrix<double, 4, 3> Jx = reprojection_jacobian(rig_, X);
  const Eigen::Vector3d row = (Jx.transpose() * Jx).ldlt().solve(Eigen::Vector3d::UnitZ());
  const Eigen::Matrix<double, 1, kCalibrationParameters> dz = (Jx * row).transpose() * parameter_jacobian(X);
  return std::sqrt(std::max((dz * cov_ * dz.transpose())(0, 0), 0.0));
}

}  // namespace naneye::recon
