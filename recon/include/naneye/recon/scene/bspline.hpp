#pragma once
// Cubic B-spline interpolation's coefficients (Unser, "Splines: a perfect fit for signal and image
// processing", IEEE Signal Processing Magazine 16(6), 1999, Box 2; Unser, Aldroubi & Eden, IEEE TSP
// 41(2), 1993). The sub-pixel matcher samples the target image between pixels; Keys' cubic there
// biases every match towards whole pixels by up to ~0.02 px on this camera's texture ("pixel
// locking", tests/scene/test_lk_affine.cpp), ~0.2 % of depth at 10 px of disparity. The cubic
// B-spline over these coefficients interpolates the same samples with a far flatter response (its
// largest error on plane waves of 4 / 6 / 10 px is 4 / 6 / 10x smaller, tests/scene/test_bspline.cpp),
// for one recursive filter pass per row and column per frame.
#include "naneye/recon/scene/features.hpp"

namespace naneye::recon::scene {

// The rectangle of an image that carries data (RawImageView's ignored padding column and edge rows
// are outside it): columns [0, cols), rows [row_begin, row_end).
struct ActiveRect {
  int cols = 0, row_begin = 0, row_end = 0;
};

// out (in.width x in.height, not aliasing in) = the coefficients c with sum_k c[k] beta3(x - k) = in
// at every pixel of `active`, the image continued beyond the rectangle's edges as its mirror image
// (whole-sample symmetric, the usual boundary: no step at the edge). Outside the rectangle `out`
// holds the mirrored coefficients, so a 4 x 4 tap set reaching over the edge reads that same
// continuation, never the padding. The rectangle must be at least 17 x 17 (std::invalid_argument
// otherwise). `scratch`: room for the rectangle's floats.
void bspline_coefficients(const GrayView& in, const ActiveRect& active, float* out, float* scratch);

// The same for one line of n >= 2 samples (in and out may be the same array): out = the coefficients
// of the line continued as its mirror image at both ends.
void bspline_coefficients_line(const float* in, int n, float* out);

// The interpolant's derivative at the samples, (c[x + 1] - c[x - 1]) / 2 (beta3'(+-1) = -+1/2,
// beta3'(0) = 0), as a filter on the samples themselves: d/dx at x = sum_k D_k in[x + k], D_k =
// (h_{k - 1} - h_{k + 1}) / 2 with h_k = sqrt(3) z1^|k| the coefficients' impulse response (the
// inverse of (1, 4, 1) / 6; Unser 1999, Box 2). Odd, |D_k| ~ 0.27^|k|: 0 beyond |k| = 12 to 1e-7.
// Its white-noise gain sum_k D_k^2 is 1.392, against the central difference's 0.5: the noise a
// gradient taken this way carries (dense_subpixel.cpp).
inline constexpr int kKnotDerivativeReach = 12;
double bspline_knot_derivative_tap(int k);

// What the interpolant does to white noise in the samples: along one axis a value at fractional
// offset f (0 <= f < 1) past a sample is sum_j eta(f + j) x_j, eta the cardinal cubic spline
// (eta(k) = delta_k; eta = sum_k h_k beta3(. - k), h as above), so the noise of values taken at one
// offset f on the whole grid has the autocorrelation, per unit of the samples' variance,
// R_f(lag) = sum_j eta(f + j) eta(f + j + lag). R_f(0), the variance's gain, is 1 at f = 0 and
// 0.756 at f = 1/2; sum over lags of R_f is 1 (eta sums to 1). Lags 0 .. kNoiseLagReach, from a
// table at 1/256 (linear between entries: ~1e-6). In 2-D the interpolant is the product of the axes'.
inline constexpr int kNoiseLagReach = 2;
double bspline_noise_autocorrelation(double f, int lag);
// The same for every lag 0 .. kNoiseLagReach at once (the same values: one table look-up set-up for
// all, for the LK's per-sample use).
void bspline_noise_autocorrelations(double f, double (&out)[kNoiseLagReach + 1]);

}  // namespace naneye::recon::scene
