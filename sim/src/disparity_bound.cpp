// The Cramér-Rao bound of a dense disparity on a textured render (disparity_bound.hpp).
#include "naneye/sim/disparity_bound.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "naneye/recon/scene/rectified_axes.hpp"

namespace naneye::sim {
namespace {

// The texture's derivative by the 8th-order central difference (Fornberg 1988): the bound needs the
// signal's own slope, and the 2-tap difference (x[+1] - x[-1]) / 2 reads sin(w) / w of it, 64 % at
// the presets' shortest wavelength (4 px, w = pi / 2), which would overstate the bound by 1.6x
// there; this one reads 97 % of it.
constexpr int kDiffReach = 4;
constexpr std::array<double, kDiffReach> kDiff{4.0 / 5, -1.0 / 5, 4.0 / 105, -1.0 / 280};

// Per seen pixel (NaN elsewhere): the texture's slope along the left epipolar line (DN per left raw
// px) and that line's scale, left raw px per rectified disparity px. Both from the right eye's ray
// through the seen point X: as the point slides along it, the left pixel moves along the epipolar
// line while the rectified disparity f B / Z_rect changes (rectified_axes.hpp).
struct EpipolarSlope {
  cv::Mat slope, px_per_disparity;
};

EpipolarSlope epipolar_slope(const recon::StereoRig& rig, const cv::Mat& clean, const cv::Mat& truth) {
  const int cols = clean.cols, rows = clean.rows;
  cv::Mat s;
  clean.convertTo(s, CV_64F);
  EpipolarSlope out{cv::Mat(rows, cols, CV_64FC1, cv::Scalar(NAN)),
                    cv::Mat(rows, cols, CV_64FC1, cv::Scalar(NAN))};
  const Eigen::Vector3d C_r = rig.right_center();
  const Eigen::RowVector3d z_rect = recon::scene::rect_from_left(rig).row(2);
  const double fB = rig.left.fx() * C_r.norm();  // the rectified focal length is the left fx
  // The stencil never reads the last column (the sensor's padding, driver/frame.hpp).
  for (int v = kDiffReach; v < rows - kDiffReach; ++v)
    for (int u = kDiffReach; u < cols - 1 - kDiffReach; ++u) {
      const double z = truth.at<double>(v, u);
      if (!std::isfinite(z)) continue;
      const auto und = rig.left.undistort(Eigen::Vector2d(u, v));
      if (!und.ok()) continue;
      const Eigen::Vector3d X = Eigen::Vector3d(und.normalized.x(), und.normalized.y(), 1.0) * z;
      // +-1 % along the right ray from its centre: ~0.1-1 px, short against the line's bending.
      const Eigen::Vector3d Yp = C_r + 1.01 * (X - C_r), Ym = C_r + 0.99 * (X - C_r);
      const Eigen::Vector2d dx = rig.left.project(Yp) - rig.left.project(Ym);
      const double dd = fB / z_rect.dot(Yp) - fB / z_rect.dot(Ym);
      if (!(dx.norm() > 0 && std::abs(dd) > 0)) continue;
      const Eigen::Vector2d e = dx.normalized();
      double gx = 0, gy = 0;
      for (int j = 1; j <= kDiffReach; ++j) {
        const double cj = kDiff[static_cast<std::size_t>(j) - 1];
        gx += cj * (s.at<double>(v, u + j) - s.at<double>(v, u - j));
        gy += cj * (s.at<double>(v + j, u) - s.at<double>(v - j, u));
      }
      out.slope.at<double>(v, u) = gx * e.x() + gy * e.y();
      out.px_per_disparity.at<double>(v, u) = dx.norm() / std::abs(dd);
    }
  return out;
}

}  // namespace

double noise_variance_dn2(const SensorSettings& s, double clean_dn) {
  const double signal = std::max(0.0, clean_dn - s.black_level_dn);
  return signal / s.gain_e_per_dn + s.read_noise_dn * s.read_noise_dn + s.column_fpn_dn * s.column_fpn_dn +
         s.dsnu_dn * s.dsnu_dn + (s.prnu * signal) * (s.prnu * signal) + 1.0 / 12;
}

cv::Mat disparity_bound(const recon::StereoRig& rig, const SensorSettings& sensor, const cv::Mat& clean_left,
                        const cv::Mat& truth, int r) {
  if (sensor.bayer) throw std::invalid_argument("disparity_bound: mono renders only");
  if (clean_left.type() != CV_16UC1 || truth.type() != CV_64FC1 || clean_left.size() != truth.size() || r < 1)
    throw std::invalid_argument(
        "disparity_bound: a CV_16UC1 frame, its CV_64FC1 truth of the same size, r >= 1");
  const EpipolarSlope ep = epipolar_slope(rig, clean_left, truth);
  cv::Mat bound(truth.size(), CV_64FC1, cv::Scalar(NAN));
  for (int v = r; v < truth.rows - r; ++v)
    for (int u = r; u < truth.cols - r; ++u) {
      const double scale = ep.px_per_disparity.at<double>(v, u);
      if (!std::isfinite(scale)) continue;
      // Least squares of the slope g on (1, level) over the window's pixels that have one: the
      // gain and offset's part of it; what is left fixes the shift. The noise variance is the
      // window's mean (uniform weights, as the matcher's box sums have), each pixel's taken as
      // independent (the column FPN is not, down a column: the bound is a little optimistic at
      // --real-sensor).
      Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
      Eigen::Vector2d b = Eigen::Vector2d::Zero();
      double gg = 0, var = 0;
      int n = 0;
      for (int dr = -r; dr <= r; ++dr)
        for (int dc = -r; dc <= r; ++dc) {
          const double g = ep.slope.at<double>(v + dr, u + dc);
          if (!std::isfinite(g)) continue;
          const double level = clean_left.at<std::uint16_t>(v + dr, u + dc);
          const Eigen::Vector2d a(1.0, level);
          A += a * a.transpose();
          b += a * g;
          gg += g * g;
          var += noise_variance_dn2(sensor, level);
          ++n;
        }
      if (n < 3 || !(A.determinant() > 0)) continue;
      const double perp = gg - b.dot(A.inverse() * b);
      if (!(perp > 0)) continue;  // a flat window fixes no shift: no bound
      // Both eyes' noise: var(d) >= (sigma_l^2 + sigma_r^2) / sum g_perp^2, in left raw px along
      // the line, then in rectified disparity px.
      bound.at<double>(v, u) = std::sqrt(2.0 * (var / n) / perp) / scale;
    }
  return bound;
}

double disparity_sigma(const recon::StereoRig& rig, const Eigen::Vector2d& left_px, double z_mm,
                       double sigma_z_mm) {
  const auto und = rig.left.undistort(left_px);
  if (!und.ok()) return NAN;
  // d = f B / Z_rect with Z_rect = Z (z_rect . ray): d d / d Z = -d / Z.
  const Eigen::Vector3d ray(und.normalized.x(), und.normalized.y(), 1.0);
  const double d =
      rig.left.fx() * rig.right_center().norm() / (z_mm * recon::scene::rect_from_left(rig).row(2).dot(ray));
  return sigma_z_mm * d / z_mm;
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
