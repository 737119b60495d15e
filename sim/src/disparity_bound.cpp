// The Cramér-Rao bound of a dense disparity on a textured render (disparity_bound.hpp).
#include "naneye/sim/disparity_bound.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>

namespace naneye::sim {
namespace {

// The texture's derivative by the 8th-order central difference (Fornberg 1988): the bound needs the
// signal's own slope, and the 2-tap difference (x[+1] - x[-1]) / 2 reads sin(w) / w of it, 64 % at
// the presets' shortest wavelength (4 px, w = pi / 2), which would overstate the bound by 1.6x
// there; this one reads 97 % of it.
constexpr int kDiffReach = 4;
constexpr std::array<double, kDiffReach> kDiff{4.0 / 5, -1.0 / 5, 4.0 / 105, -1.0 / 280};

}  // namespace

double noise_variance_dn2(const SensorSettings& s, double clean_dn) {
  const double signal = std::max(0.0, clean_dn - s.black_level_dn);
  return signal / s.gain_e_per_dn + s.read_noise_dn * s.read_noise_dn + s.column_fpn_dn * s.column_fpn_dn +
         s.dsnu_dn * s.dsnu_dn + (s.prnu * signal) * (s.prnu * signal) + 1.0 / 12;
}

cv::Mat disparity_bound(const recon::StereoRig& rig, const SensorSettings& sensor, const cv::Mat& clean,
                        const cv::Mat& truth, int r) {
  const int w = clean.cols, h = clean.rows;
  cv::Mat s(h, w, CV_64FC1), ge(h, w, CV_64FC1, cv::Scalar(0)), speed(h, w, CV_64FC1, cv::Scalar(NAN));
  clean.convertTo(s, CV_64F);
  const Eigen::Vector3d C_r = -rig.R.transpose() * rig.T;  // the right centre in the left frame
  for (int v = kDiffReach; v < h - kDiffReach; ++v)
    for (int u = kDiffReach; u < w - kDiffReach; ++u) {
      const double z = truth.at<double>(v, u);
      if (!std::isfinite(z)) continue;
      const auto und = rig.left.undistort(Eigen::Vector2d(u, v));
      if (!und.ok()) continue;
      const Eigen::Vector3d X = Eigen::Vector3d(und.normalized.x(), und.normalized.y(), 1.0) * z;
      // The left epipolar direction: the image of the line from X towards the right centre.
      const Eigen::Vector2d x0 = rig.left.project(X), x1 = rig.left.project(X + 1e-3 * (C_r - X));
      const Eigen::Vector2d e = (x1 - x0).normalized();
      double gx = 0, gy = 0;
      for (int j = 1; j <= kDiffReach; ++j) {
        const double cj = kDiff[static_cast<std::size_t>(j) - 1];
        gx += cj * (s.at<double>(v, u + j) - s.at<double>(v, u - j));
        gy += cj * (s.at<double>(v + j, u) - s.at<double>(v - j, u));
      }
      ge.at<double>(v, u) = gx * e.x() + gy * e.y();
      // The right curve's speed, raw px per unit inverse depth (mm^-1), by a +-1 % central difference.
      const Eigen::Vector3d ray = X / z;
      const auto right_at = [&](double wi) { return rig.right.project(rig.R * ray / wi + rig.T); };
      const double w0 = 1.0 / z;
      speed.at<double>(v, u) = (right_at(1.01 * w0) - right_at(0.99 * w0)).norm() / (0.02 * w0);
    }
  const double fB = rig.left.fx() * rig.T.norm();  // rectified disparity per unit inverse depth
  cv::Mat bound(h, w, CV_64FC1, cv::Scalar(NAN));
  for (int v = r; v < h - r; ++v)
    for (int u = r; u < w - r; ++u) {
      if (!std::isfinite(speed.at<double>(v, u))) continue;
      // Least squares of g on (1, s) over the window's seen pixels; sum of the residual g^2.
      Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
      Eigen::Vector2d b = Eigen::Vector2d::Zero();
      double gg = 0, var = 0;
      int n = 0;
      for (int dr = -r; dr <= r; ++dr)
        for (int dc = -r; dc <= r; ++dc) {
          if (!std::isfinite(truth.at<double>(v + dr, u + dc))) continue;
          const double sv = s.at<double>(v + dr, u + dc), g = ge.at<double>(v + dr, u + dc);
          const Eigen::Vector2d a(1.0, sv);
          A += a * a.transpose();
          b += a * g;
          gg += g * g;
          var += noise_variance_dn2(sensor, sv);
          ++n;
        }
      if (n < 3) continue;
      if (!(A.determinant() > 0)) continue;
      const double perp = gg - b.dot(A.inverse() * b);
      const double sigma_raw = std::sqrt(2.0 * (var / n) / std::max(perp, 1e-300));
      bound.at<double>(v, u) = sigma_raw / speed.at<double>(v, u) * fB;
    }
  return bound;
}

SensorSettings noise_free_twin(const SensorSettings& s) {
  SensorSettings quiet = s;
  quiet.noise = false;
  quiet.column_fpn_dn = quiet.dsnu_dn = quiet.prnu = 0;
  quiet.defect_pixels = 0;
  quiet.reset_rows = 0;
  return quiet;
}

}  // namespace naneye::sim
