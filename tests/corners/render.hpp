#pragma once
// A small checkerboard renderer for the corner tests and the corner benchmark, until the simulator
// (naneye_sim) lands: a 9 x 7 board (white margin, dim background) seen through the exact
// CameraModel, 4 x 4 supersampled (pixel integration), Gaussian PSF, cos^4 vignetting, a lighting
// gradient, shot + read noise, 10-bit, mono or GRBG Bayer. Truth: the projected inner corners.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "naneye/recon/camera.hpp"
#include "naneye/recon/rig.hpp"

namespace naneye::test {

struct BoardPose {
  Eigen::Matrix3d R =
      Eigen::Matrix3d::Identity();  // X_cam = R X_board + t, board corner (i,j) at (j s, i s, 0)
  Eigen::Vector3d t{0, 0, 70};
};

struct RenderSpec {
  BoardPose pose;
  bool board = true;
  bool bayer = false;
  bool noise = true;
  std::uint64_t seed = 1;
  double blur_sigma_px = 0.41;
  int square_rows = 7, square_cols = 9;
  double square_mm = 5.99, border_squares = 0.5;
  double white_dn = 760, black_level_dn = 48, black = 0.07, background = 0.12;
  double gain_e_per_dn = 12, read_noise_dn = 1.8;
};

struct Rendered {
  std::vector<std::uint16_t> pixels;   // 250 x 250, column 249 padding (0)
  std::vector<Eigen::Vector2d> truth;  // inner corners row-major (square_cols - 1 per row)
  bool all_in_view = false;            // every inner corner at least 4 px inside the usable area
};

inline Rendered render_board(const recon::CameraModel& cam, const RenderSpec& s) {
  constexpr int kSS = 4, W = 250, H = 250;
  // The radial model's inverse as a dense 1-D table of r / r_d (exact to ~1e-9 between samples).
  const double rd_max = cam.fold_radius_distorted().value_or(2.0) * 0.9999;
  constexpr int kTable = 8192;
  std::vector<double> ratio(kTable + 1);
  for (int i = 0; i <= kTable; ++i) {
    const double rd = std::max(rd_max * i / kTable, 1e-9);
    const auto u = cam.undistort_distorted({rd, 0});
    ratio[static_cast<std::size_t>(i)] = u.ok() ? u.normalized.x() / rd : 0.0;
  }
  const Eigen::Vector3d n = s.pose.R.col(2);
  const double nt = n.dot(s.pose.t);
  const double sq = s.square_mm;
  const double u_lo = -(1 + s.border_squares) * sq, u_hi = (s.square_cols - 1 + s.border_squares) * sq;
  const double v_lo = -(1 + s.border_squares) * sq, v_hi = (s.square_rows - 1 + s.border_squares) * sq;
  cv::Mat hi(H * kSS, W * kSS, CV_32F);
  for (int r = 0; r < H * kSS; ++r) {
    for (int c = 0; c < W * kSS; ++c) {
      const Eigen::Vector2d px((c + 0.5) / kSS - 0.5, (r + 0.5) / kSS - 0.5);
      const Eigen::Vector2d xd = cam.from_pixel(px);
      const double rd = xd.norm();
      float val = 0.0f;
      if (rd < rd_max) {
        const double f = rd / rd_max * kTable;
        const int i = std::min(static_cast<int>(f), kTable - 1);
        const double a = f - i;
        const Eigen::Vector2d xn =
            xd * ((1 - a) * ratio[static_cast<std::size_t>(i)] + a * ratio[static_cast<std::size_t>(i) + 1]);
        const Eigen::Vector3d ray(xn.x(), xn.y(), 1.0);
        double radiance = s.background;
        const double denom = n.dot(ray);
        if (s.board && std::abs(denom) > 1e-9) {
          const double lambda = nt / denom;
          if (lambda > 0) {
            const Eigen::Vector3d b = s.pose.R.transpose() * (lambda * ray - s.pose.t);
            if (b.x() >= u_lo && b.x() < u_hi && b.y() >= v_lo && b.y() < v_hi) {
              radiance = 1.0;
              const int sc = static_cast<int>(std::floor(b.x() / sq)) + 1;
              const int sr = static_cast<int>(std::floor(b.y() / sq)) + 1;
              if (sc >= 0 && sc < s.square_cols && sr >= 0 && sr < s.square_rows && (sc + sr) % 2 == 0) {
                radiance = s.black;
              }
              // A light beside the lens: a gentle gradient across the board.
              radiance *= 1.0 + 0.004 * b.x() - 0.003 * b.y();
            }
          }
        }
        const double r2 = xn.squaredNorm();
        val = static_cast<float>(radiance / ((1 + r2) * (1 + r2)));  // cos^4 fall-off
      }
      hi.at<float>(r, c) = val;
    }
  }
  if (s.blur_sigma_px > 0) cv::GaussianBlur(hi, hi, cv::Size(0, 0), s.blur_sigma_px * kSS);
  cv::Mat lo;
  cv::resize(hi, lo, cv::Size(W, H), 0, 0, cv::INTER_AREA);
  Rendered out;
  out.pixels.assign(W * H, 0);
  std::mt19937_64 rng(s.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  static constexpr double kGain[3] = {0.78, 1.0, 0.62};  // R G B
  for (int r = 0; r < H; ++r) {
    for (int c = 0; c < W - 1; ++c) {
      double g = 1.0;
      if (s.bayer) g = (r % 2 == 0) ? (c % 2 == 0 ? kGain[1] : kGain[0]) : (c % 2 == 0 ? kGain[2] : kGain[1]);
      const double sig = s.white_dn * g * lo.at<float>(r, c);
      double dn = s.black_level_dn + sig;
      if (s.noise) {
        dn +=
            gauss(rng) * std::sqrt(std::max(sig, 0.0) / s.gain_e_per_dn + s.read_noise_dn * s.read_noise_dn);
      }
      out.pixels[static_cast<std::size_t>(r * W + c)] =
          static_cast<std::uint16_t>(std::clamp(std::lround(dn), 0L, 1023L));
    }
  }
  out.all_in_view = s.board;
  for (int i = 0; i < s.square_rows - 1; ++i) {
    for (int j = 0; j < s.square_cols - 1; ++j) {
      const Eigen::Vector3d X = s.pose.R * Eigen::Vector3d(j * sq, i * sq, 0) + s.pose.t;
      const Eigen::Vector2d p = cam.project(X);
      out.truth.push_back(p);
      if (!(p.x() >= 4 && p.x() <= W - 6 && p.y() >= 5 && p.y() <= H - 6) || !cam.in_domain(p))
        out.all_in_view = false;
    }
  }
  return out;
}

// A random pose of the paper's Dataset 3 kind: grid centre at 58-85 mm, tilt up to 40 degrees about
// an axis in the board plane, in-plane turn up to +-20 degrees, grid centre near the optical axis.
inline BoardPose random_pose(std::mt19937_64& rng, double z_lo = 58, double z_hi = 85,
                             double max_tilt_deg = 40, double max_offset_mm = 4) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const double kPi = 3.14159265358979323846;
  const double z = z_lo + (z_hi - z_lo) * U(rng);
  const double tilt = max_tilt_deg * kPi / 180 * std::sqrt(U(rng));
  const double axis_angle = 2 * kPi * U(rng);
  const double spin = (U(rng) - 0.5) * 40 * kPi / 180;
  const Eigen::Matrix3d R =
      (Eigen::AngleAxisd(tilt, Eigen::Vector3d(std::cos(axis_angle), std::sin(axis_angle), 0)) *
       Eigen::AngleAxisd(spin, Eigen::Vector3d::UnitZ()))
          .toRotationMatrix();
  const Eigen::Vector3d centre_board(3.5 * 5.99, 2.5 * 5.99, 0);
  const Eigen::Vector3d centre_cam((U(rng) - 0.5) * 2 * max_offset_mm, (U(rng) - 0.5) * 2 * max_offset_mm, z);
  BoardPose p;
  p.R = R;
  p.t = centre_cam - R * centre_board;
  return p;
}

// The same board seen by the right camera of a rig (X_right = R X_left + T).
inline BoardPose to_right(const recon::StereoRig& rig, const BoardPose& left) {
  BoardPose p;
  p.R = rig.R * left.R;
  p.t = rig.R * left.t + rig.T;
  return p;
}

}  // namespace naneye::test
