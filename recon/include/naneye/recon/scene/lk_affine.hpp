#pragma once
// Sub-pixel refinement of a match on the raw pixels: inverse-compositional Lucas-Kanade with an
// affine warp (Baker & Matthews, "Lucas-Kanade 20 years on", IJCV 56(3), 2004, Sec. 3.2), the
// template being the source window at a pixel centre, each warped target window normalised to the
// template's mean and contrast (the eyes' exposure and vignetting differ), and the translation's
// covariance from the Gauss-Newton Hessian and the residual noise: Sigma = s^2 H^-1, s^2 = SSR / (N - 8)
// (6 warp parameters, 2 for the normalisation).
#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "naneye/recon/scene/features.hpp"

namespace naneye::recon::scene {

// px; the widest window refine_affine takes (21 x 21): a wider one is never converged.
inline constexpr int kMaxLkRadius = 10;

struct LkSettings {
  int radius = 4;  // px; template window (2 radius + 1)^2, at most kMaxLkRadius
  int max_iterations = 20;
  double stop_step_px = 5e-3;  // px; stop when the centre moves less than this
  double max_travel_px = 2.5;  // px; from the start: beyond, the coarse match was wrong
  // The images' noise is white noise filtered by this 3x3 kernel (row-major; sums of squares need
  // not be 1): the identity for a mono sensor, raw_to_luminance's binomial for a Bayer one, whose
  // neighbouring luminance pixels share raw noise. The covariance is then the sandwich
  // H^-1 (sum_j (b * SD)_j (b * SD)_j^T) H^-1 s^2 / |b|^2 instead of s^2 H^-1.
  std::array<float, 9> noise_kernel{0, 0, 0, 0, 1, 0, 0, 0, 0};
  // px; > 0: the result also reports the SSR of the pixels farther than this from the centre
  // (Chebyshev distance), the ring a wider window adds to a narrower one (sparse.cpp's window test).
  int inner_radius = 0;
  // true: the result also reports LkResult::curvature_gain (the sparse path's curvature model,
  // sparse_curvature.cpp), 54 more dot products per fit.
  bool curvature_gain = false;
  static std::array<float, 9> binomial3() {
    return {1 / 16.f, 2 / 16.f, 1 / 16.f, 2 / 16.f, 4 / 16.f, 2 / 16.f, 1 / 16.f, 2 / 16.f, 1 / 16.f};
  }
};

struct LkResult {
  bool converged = false;
  Eigen::Vector2d px{0, 0};                         // target raw pixel of the template centre
  Eigen::Matrix2d A = Eigen::Matrix2d::Identity();  // the warp's linear part
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();    // px^2, covariance of px
  double zncc = 0;                                  // of the final warped window
  // The final residual in the template's grey levels (DN^2): over the window, and over the pixels
  // beyond LkSettings::inner_radius (0 when that is 0). Both images' noise is in it.
  double ssr_dn2 = 0, ssr_outer_dn2 = 0;
  // The residual's degrees of freedom, E[SSR] / the noise's variance per pixel: N - 8 for white
  // noise, N - tr(P C) under LkSettings::noise_kernel, each less the share of the right eye's noise
  // the target's interpolant smooths away at the samples' fractional places (lk_affine.cpp).
  double noise_dof = 0;
  // With LkSettings::inner_radius: the covariance of (this fit's px - the px of the same fit over the
  // inner pixels only) per unit residual variance (in the normalised template's units: DN^2 divided
  // by template_ss_dn2), px^2; and the template's sum of squared deviations, DN^2.
  Eigen::Matrix2d diff_cov_unit = Eigen::Matrix2d::Zero();
  double template_ss_dn2 = 0;
  // With LkSettings::curvature_gain: how far px moves when the target's displacement has a part
  // beyond the affine, d_k = 1/2 (q_k^T Q q_k) v at template offset q_k = (dc, dr) (a surface's
  // curvature: Q symmetric, px / px^2; v a direction in the target, px): by
  // sum_m Q_m curvature_gain[m] v over m = (xx, xy, yy). Linearised (the Gauss-Newton fixed point's
  // sensitivity to a residual g_k . d_k): A P_t sum_k sd_k g_k^T (1/2 dc^2, dc dr, 1/2 dr^2)_m,
  // P_t the translation's rows of the solve, g_k the template's gradient in the warp's domain.
  // False where LkSettings::curvature_gain was asked but the window has none to give (lk_affine.cpp).
  bool has_curvature_gain = false;
  std::array<Eigen::Matrix2d, 3> curvature_gain{Eigen::Matrix2d::Zero(), Eigen::Matrix2d::Zero(),
                                                Eigen::Matrix2d::Zero()};
  int iterations = 0;
};

// Satterthwaite's (1946) factor for a sum of squares of noise filtered by `kernel` (LkSettings'
// noise_kernel): sum over lags of the noise autocorrelation squared, sum_l rho(l)^2. A residual sum
// over N pixels then behaves as a chi-square with N / factor degrees of freedom (1 for white noise,
// 3.78 for the Bayer binomial).
double noise_dof_factor(const std::array<float, 9>& kernel);

// `tgx`, `tgy`: central-difference gradients of `src`. `dst`: the target's cubic B-spline
// coefficients (bspline_coefficients), which the warped window samples. `dst_usable`: non-zero where a window
// of radius + 1 around the pixel lies inside the target's domain; the warp must keep its centre there. The
// warp is affine in q: without `shape`, q = the template offset (dc, dr) and the start is A0 q + start; with
// `shape` (one entry per template pixel, row-major), q = the pixel's predicted place in the target relative
// to the centre (the exact model's map at the coarse depth, which an affine in raw pixels cannot follow near
// the image edges), the start is q + start and A0 is that map's Jacobian at the centre. `start_linear`: the
// warp's linear part to start from (another refinement's A, e.g. a narrower window's) instead of A0 (without
// `shape`) or I (with it).
LkResult refine_affine(const GrayView& src, const float* tgx, const float* tgy, int u, int v,
                       const GrayView& dst, const std::uint8_t* dst_usable, const Eigen::Vector2d& start,
                       const Eigen::Matrix2d& A0, const Eigen::Vector2d* shape, const LkSettings& s,
                       const Eigen::Matrix2d* start_linear = nullptr);

}  // namespace naneye::recon::scene
