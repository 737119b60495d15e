#pragma once
#include <cstdint>
// Sub-pixel refinement of one checkerboard corner: a least-squares fit (Levenberg-Marquardt) of a
// blurred saddle to the pixels of a small window.
//
// Why this model: the two board edges through a corner are straight lines on the undistorted image
// plane (a plane seen by a pinhole), but curved in the raw image under this lens' strong barrel
// distortion (paper Eq. 5). The window's pixels are therefore mapped to local undistorted
// coordinates y = J (undistort(p) - undistort(c)) with J = d pixel / d normalized at the window
// centre c, so y ~ p - c to first order and the edges are exactly straight in y. The intensity is
//   I = a + g . d + (b + h . d) * erf(u1 / (sqrt2 s)) * erf(u2 / (sqrt2 s)),  d = p - c,
// u_k = n_k . (y - q): a Gaussian-blurred ideal corner (exact for perpendicular edges, Gaussian PSF)
// with a linear shading term on both the mean and the contrast (vignetting, lighting). The corner
// is q, mapped back to raw pixels with the exact model (distort + K).
#include <Eigen/Core>

#include "naneye/recon/camera/camera_model.hpp"

namespace naneye::recon {

// The linear part of the model (mean a, contrast b, their gradients per raw pixel) referred to the
// corner itself, so that it does not depend on the fit window: a later fit of the same corner (the
// final pass, the next frame) starts with it instead of solving for it first.
struct SaddleShading {
  double a = 0, gx = 0, gy = 0, b = 0, hx = 0, hy = 0;
  bool valid = false;
};

struct SaddleInit {
  Eigen::Vector2d px{0, 0};       // initial corner, raw pixel
  double theta1 = 0, theta2 = 0;  // normals of the two edges (radians, local undistorted pixels)
  double sigma = 0.8;
  SaddleShading shading{};  // a start for the linear terms, referred to `shading_at` (fit_saddle_fast)
  Eigen::Vector2d shading_at{0, 0};
};

struct SaddleFit {
  Eigen::Vector2d px{0, 0};
  double theta1 = 0, theta2 = 0, sigma = 0;
  double contrast = 0;  // |b|: half the black-white difference at the corner
  double rms = 0;       // residual RMS, DN
  int iterations = 0;
  int outliers = 0;   // pixels dropped as outliers (defect pixels)
  double weight = 0;  // sum of the window's pixel weights (taper included): the residual's sample size
  bool converged = false;
  bool undistorted = false;  // false: fitted in raw pixels (window beyond the model's fold)
  SaddleShading shading{};   // referred to px (fit_saddle_fast only)
  // The corner's position variance per unit of pixel noise variance (px^2 / DN^2): the larger
  // eigenvalue of the position block of (J' W J)^-1 at the solution (fit_saddle_fast only; 0: not
  // computed). Times the noise variance, the position's variance as least squares gives it
  // (Gauss-Markov): how well this window, this blur and this contrast hold the corner.
  double position_var_per_noise = 0;
  // Fitted as the blurred checkerboard's fundamental (fit_sine_corner, corners/sine_fit.hpp), not as
  // one blurred X-junction: sigma and the edge normals are not fitted.
  bool harmonic = false;
};

// A read-only float image with the rectangle [col 0, col_end) x [row_begin, row_end) usable.
struct LumaView {
  const float* data = nullptr;
  int width = 0, height = 0;
  int row_begin = 0, row_end = 0, col_end = 0;
  // Optional, width x height: nonzero where the value mixes a clipped raw pixel (a Bayer luminance's
  // 3 x 3 filter reaches one) and is no measure of the light; the fit leaves such pixels out, as it
  // does any value at the clip.
  const std::uint8_t* clipped = nullptr;
  float at(int r, int c) const { return data[r * width + c]; }
};

// Fits one corner with the pixels within `radius` (Chebyshev, from init.px; a 1 px taper beyond).
// Returns false when the window does not fit in the usable area or the fit diverges (left the
// window, degenerate edges). `max_iterations` bounds the LM iterations; the fit stops when the
// corner moves less than `tolerance_px` in one step (default 1e-4 px: two orders below the
// noise-limited accuracy).
bool fit_saddle(const LumaView& img, const CameraModel& cam, const SaddleInit& init, double radius,
                int max_iterations, SaddleFit& out, double tolerance_px = 1e-4);

}  // namespace naneye::recon
