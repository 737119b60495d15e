#pragma once
// The calibration's depth sigma (calibration_uncertainty.hpp) for every pixel of a dense map: the
// exact propagation costs 0.27 us a point (bench_recon BM_CalibrationDepthSigma), ~13 ms for the
// ~47 000 depths of a map, most of the dense path's own time. A dense map's pixels are the left raw grid's,
// so the table holds, per pixel, the sigma along its ray as a function of depth, once per rig:
// - per pixel, sigma_Z / Z^2 as a Chebyshev interpolant in inverse depth w = 1/Z over
//   [1/z_max, 1/z_min] (the dense band's range), from its values at depth_terms Chebyshev nodes
//   (Trefethen, Approximation Theory and Approximation Practice, ch. 3-4);
// - sigma_Z / Z^2 because a disparity-like error gives it exactly (Z = f B / d, dZ = Z^2 / (f B)
//   dd) and the rest (focal, baseline, the right pixel's drift along the epipolar curve) is
//   analytic in w with terms of order |T| w (<= 0.2 at 5 mm): 8 terms leave < 2e-4 of the sigma
//   (CalibrationSigmaTable.*, over every pixel both eyes see at depths across the band);
// - a spatial grid does not serve: toward the fold the sigma grows without bound (the projection's
//   radial derivative vanishes there) and even at 50-90 px from the centre it changes by 1 % within
//   8 px (docs/scene.md, "The calibration sigma per pixel").
// Outside the table (depths beyond the band, pixels beyond the fold or the image) the exact
// propagation answers, so a value is always the calibration's own.
#include <Eigen/Core>
#include <optional>
#include <vector>

#include "naneye/recon/camera/rig.hpp"
#include "naneye/recon/geometry/calibration_uncertainty.hpp"

namespace naneye::recon {

struct CalibrationSigmaTableSettings {
  double z_min_mm = 5, z_max_mm = 150;  // mm; the depths tabulated (the dense path's band)
  // Chebyshev terms per pixel: 8 leave < 2e-4 of the sigma, 6 ~2e-3, 4 ~1e-2 (the test's
  // measurement, docs/scene.md); each term costs a float per pixel and an exact propagation per
  // pixel at construction (8: 2 MB, 124 ms for 250 x 250, bench_recon BM_CalibrationSigmaTable).
  int depth_terms = 8;
  // Throws std::invalid_argument when a setting cannot give a table.
  void validate() const;
};

class CalibrationSigmaTable {
 public:
  // Empty when the rig's calibration has no covariance (CalibrationUncertainty::of).
  static std::optional<CalibrationSigmaTable> of(const StereoRig& rig,
                                                 const CalibrationSigmaTableSettings& s = {});
  CalibrationSigmaTable(const StereoRig& rig, const CalibrationUncertainty& u,
                        const CalibrationSigmaTableSettings& s = {});

  // The one-sigma depth (mm) the calibration allows for the point X (left frame, mm) seen at the
  // left raw pixel (u, v), X on that pixel's ray.
  float depth_sigma_mm(int u, int v, const Eigen::Vector3d& X) const {
    const double t = (2.0 / X.z() - w_sum_) / w_span_;  // w mapped onto [-1, 1]
    if (!(t >= -1 && t <= 1) || u < 0 || v < 0 || u >= width_ || v >= height_) return exact(X);
    const float* c = &c_[(static_cast<std::size_t>(v) * width_ + u) * n_];
    if (!(c[0] == c[0])) return exact(X);  // NaN: no ray at this pixel when tabulating
    // Clenshaw's recurrence for sum c_j T_j(t).
    const float tf = static_cast<float>(t);
    float b1 = 0, b2 = 0;
    for (int j = n_ - 1; j >= 1; --j) {
      const float b0 = c[j] + 2 * tf * b1 - b2;
      b2 = b1;
      b1 = b0;
    }
    return static_cast<float>((c[0] + tf * b1 - b2) * X.z() * X.z());
  }

  const CalibrationSigmaTableSettings& settings() const { return s_; }

 private:
  float exact(const Eigen::Vector3d& X) const { return static_cast<float>(u_.depth_sigma_mm(X)); }

  CalibrationUncertainty u_;
  CalibrationSigmaTableSettings s_;
  int width_ = 0, height_ = 0, n_ = 0;
  double w_sum_ = 0, w_span_ = 1;  // 1/z_min + 1/z_max and 1/z_min - 1/z_max
  std::vector<float> c_;           // [v][u][term]: Chebyshev coefficients of sigma_Z / Z^2 (mm^-1)
};

}  // namespace naneye::recon
