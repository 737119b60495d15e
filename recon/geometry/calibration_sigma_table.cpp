#include "naneye/recon/geometry/calibration_sigma_table.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace naneye::recon {

void CalibrationSigmaTableSettings::validate() const {
  if (!(z_min_mm > 0 && z_max_mm > z_min_mm && std::isfinite(z_max_mm)))
    throw std::invalid_argument("calibration sigma table: need 0 < z_min_mm < z_max_mm, got " +
                                std::to_string(z_min_mm) + ", " + std::to_string(z_max_mm));
  if (depth_terms < 2 || depth_terms > 32)
    throw std::invalid_argument("calibration sigma table: depth_terms must lie in [2, 32], got " +
                                std::to_string(depth_terms));
}

std::optional<CalibrationSigmaTable> CalibrationSigmaTable::of(const StereoRig& rig,
                                                               const CalibrationSigmaTableSettings& s) {
  const auto u = CalibrationUncertainty::of(rig);
  if (!u) return std::nullopt;
  return CalibrationSigmaTable(rig, *u, s);
}

CalibrationSigmaTable::CalibrationSigmaTable(const StereoRig& rig, const CalibrationUncertainty& u,
                                             const CalibrationSigmaTableSettings& s)
    : u_(u), s_(s) {
  s_.validate();
  const CameraModel& cam = rig.left;
  width_ = cam.width();
  height_ = cam.height();
  n_ = s_.depth_terms;
  w_sum_ = 1.0 / s_.z_min_mm + 1.0 / s_.z_max_mm;
  w_span_ = 1.0 / s_.z_min_mm - 1.0 / s_.z_max_mm;
  // The Chebyshev nodes t_k = cos(pi (k + 1/2) / n) and T_j(t_k) = cos(j pi (k + 1/2) / n): the
  // coefficients are c_j = (2 - [j = 0]) / n sum_k f(t_k) T_j(t_k) (discrete orthogonality).
  std::vector<double> T(static_cast<std::size_t>(n_) * n_), z(static_cast<std::size_t>(n_)), f(z.size());
  for (int k = 0; k < n_; ++k) {
    const double a = std::numbers::pi * (k + 0.5) / n_;
    z[static_cast<std::size_t>(k)] = 2.0 / (w_sum_ + std::cos(a) * w_span_);
    for (int j = 0; j < n_; ++j) T[static_cast<std::size_t>(j) * n_ + k] = std::cos(j * a);
  }
  c_.assign(static_cast<std::size_t>(width_) * height_ * n_, std::numeric_limits<float>::quiet_NaN());
  for (int v = 0; v < height_; ++v)
    for (int c = 0; c < width_; ++c) {
      const Undistorted ray = cam.undistort({c, v});
      if (!ray.ok()) continue;  // beyond the fold: the exact propagation answers (no depth there)
      for (std::size_t k = 0; k < z.size(); ++k)
        f[k] =
            u_.depth_sigma_mm(Eigen::Vector3d(ray.normalized.x() * z[k], ray.normalized.y() * z[k], z[k])) /
            (z[k] * z[k]);
      float* out = &c_[(static_cast<std::size_t>(v) * width_ + c) * n_];
      for (int j = 0; j < n_; ++j) {
        double sum = 0;
        for (int k = 0; k < n_; ++k)
          sum += f[static_cast<std::size_t>(k)] * T[static_cast<std::size_t>(j) * n_ + k];
        out[j] = static_cast<float>((j == 0 ? 1.0 : 2.0) / n_ * sum);
      }
    }
}

}  // namespace naneye::recon
