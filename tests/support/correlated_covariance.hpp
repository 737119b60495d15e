#pragma once
// A calibration covariance to test the calibration sigma's propagation with: the paper's sigmas
// (om 1 mrad and the tangential terms 1e-4, which the paper does not give) and strong, random
// correlations, scaled by `scale`. The paper's files carry marginal sigmas only, and the
// correlations are what matter most for a stereo point (docs/calibration.md).
#include <Eigen/Core>
#include <random>

#include "naneye/recon/geometry/calibration_uncertainty.hpp"

namespace naneye::test {

inline recon::CalibrationCovariance correlated_covariance(const recon::StereoRig& rig, double scale,
                                                          unsigned seed) {
  using Params = Eigen::Matrix<double, recon::kCalibrationParameters, 1>;
  const auto u = recon::CalibrationUncertainty::assuming_independent_sigmas(rig);
  Params sd = u->covariance().diagonal().cwiseSqrt();
  sd.segment<3>(recon::kCalibrationOm).setConstant(1e-3);
  sd(recon::kCalibrationLeft + 6) = sd(recon::kCalibrationLeft + 7) = sd(recon::kCalibrationRight + 6) =
      sd(recon::kCalibrationRight + 7) = 1e-4;
  std::mt19937 rng(seed);
  std::normal_distribution<double> n;
  Eigen::MatrixXd A(recon::kCalibrationParameters, recon::kCalibrationParameters + 4);
  for (int i = 0; i < A.size(); ++i) A(i) = n(rng);
  Eigen::MatrixXd C = A * A.transpose();
  const Eigen::VectorXd inv = C.diagonal().cwiseSqrt().cwiseInverse();
  C = inv.asDiagonal() * C * inv.asDiagonal();  // a correlation matrix
  const Params s = scale * sd;
  return s.asDiagonal() * C * s.asDiagonal();
}

}  // namespace naneye::test
