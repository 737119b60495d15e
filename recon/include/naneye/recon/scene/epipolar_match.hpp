#pragma once
// Matching a pixel of one eye along its epipolar curve in the other eye's raw image (docs/scene.md).
// With this rig's distortion the epipolar "line" is a curve: the ray of the pixel, X(w) = (x, 1) / w
// for inverse depth w, goes through the exact model of the other camera, x_b(w) ~ R (x, 1) + T w,
// then distortion and K (paper Eq. 5-6). It is sampled uniformly in w over [1 / z_max, 1 / z_min],
// at about one sample per step_px of the other image.
#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "naneye/recon/camera/camera_model.hpp"
#include "naneye/recon/scene/features.hpp"

namespace naneye::recon::scene {

struct EpipolarCurve {
  static constexpr int kMaxSamples = 160;
  int n = 0;
  std::array<Eigen::Vector2d, kMaxSamples> px;  // raw pixels in the other image
  std::array<double, kMaxSamples> w;            // inverse depth (1/mm) in the source camera's frame
  std::array<bool, kMaxSamples> inside;         // inside the other camera's model domain (no fold)
};

// xn: the source pixel's undistorted normalized point; (R, T) take the source frame to the other's.
void sample_epipolar_curve(const CameraModel& other, const Eigen::Matrix3d& R, const Eigen::Vector3d& T,
                           const Eigen::Vector2d& xn, double w_min, double w_max, double step_px,
                           EpipolarCurve& out);

struct CurveMatch {
  bool found = false;        // some sample had a full, usable window
  double best = -1;          // ZNCC of the best sample
  double second = -1;        // best ZNCC beyond the best's lobe: another peak (the ambiguity)
  double index = -1;         // fractional sample index (a parabola through the best three)
  Eigen::Vector2d px{0, 0};  // raw pixel at `index` (linear between samples)
  double w = 0;
};

// ZNCC of the (2 radius + 1)^2 window of `src` around (u, v) against windows of `dst` centred at
// the nearest pixel of each sample. `dst_usable`: non-zero where such a window lies in the domain.
// `dst_inv_norm` (optional, from window_inverse_norms): 1 / |I - mean| of every dst window, so that
// each sample costs one dot product.
CurveMatch match_along_curve(const GrayView& src, int u, int v, const GrayView& dst,
                             const std::uint8_t* dst_usable, const EpipolarCurve& curve, int radius,
                             const float* dst_inv_norm = nullptr);

// Per pixel, 1 / sqrt(sum (I - mean)^2) over its (2 radius + 1)^2 window where `usable`, else 0.
// `scratch` holds 2 w doubles (column sums and sums of squares).
void window_inverse_norms(const GrayView& img, int radius, const std::uint8_t* usable, float* out,
                          double* scratch);

}  // namespace naneye::recon::scene
