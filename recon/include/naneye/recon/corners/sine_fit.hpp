#pragma once
// The corner of a board whose squares are only a few blurs across (a far board: squares of 4-6 px
// under the real NanEye's ~1-1.3 px blur), where no window holds one X-junction alone: the fit of
// the blurred checkerboard's fundamental over one to two periods.
//
// Why this model: a checkerboard is sign(sin(pi u)) sign(sin(pi v)) in grid coordinates (u, v)
// (integers on its lines), i.e. (4/pi)^2 sum over odd k, l of sin(k pi u) sin(l pi v) / (k l). A
// Gaussian blur of sigma passes harmonic k of the period 2s with the gain
// exp(-2 pi^2 k^2 sigma^2 / (2s)^2): at s = 4 px and sigma 1.0-1.3 px the fundamental keeps
// 0.73-0.59 of its amplitude and the third harmonic 0.06-0.01 (over 3), so the image there is, to a
// few percent of its contrast,
//   I = a + g . d + (b + h . d) sin(pi u) sin(pi v) + c cos(pi u) cos(pi v),  (u, v) = M (y - q),
// y the window's local undistorted coordinates (as in corners/refine.hpp: the board's lines are
// straight there), q the corner, M the inverse of the grid's local steps (fitted: 4 parameters),
// and the same linear shading of the mean and of the amplitude as the saddle fit. The c term: the
// fundamental is two plane waves, sin sin = (cos pi(u - v) - cos pi(u + v)) / 2, and a blur that
// is no isotropic Gaussian (the pixel's square aperture) or a grid that is no square
// (foreshortening, skew) passes them with different gains; their difference is c cos cos (on
// bench_conditions' 4 px boards without noise it took the residual from 16 to 4 DN, 7 % to 2 % of
// b). (The board maps to y by a homography; its two perspective terms were tried and not kept: on
// these windows of one to two periods they cost more in the corner's conditioning than they
// removed.) Every harmonic left out is odd in u and in v about the corner, as the fundamental is,
// so over a window centred on the corner it is orthogonal to the position's derivatives (odd in one
// coordinate, even in the other): it adds to the residual, not to the corner's bias; c cos cos is
// even in both, likewise. The model has no edge to cut out of the window: all of it is
// informative. The residual test of the detector decides whether it holds.
#include <Eigen/Core>

#include "naneye/recon/corners/fast_fit.hpp"

namespace naneye::recon {

struct SineInit {
  Eigen::Vector2d px{0, 0};  // initial corner, raw pixel
  // The grid's local steps (raw px): to the next column and to the next row.
  Eigen::Vector2d step_col{4, 0}, step_row{0, 4};
  // The window in grid coordinates: |u| <= extent_col, |v| <= extent_row steps from the corner (a
  // 1 px taper beyond), symmetric about it so that the harmonics left out stay orthogonal to the
  // position (but at the border, below).
  double extent_col = 1.25, extent_row = 1.25;
  // At the board's border the window keeps at most `border_extent` steps on the outer side (the
  // board's last squares end one step beyond its last inner corners) and extent_* inward. The
  // border lies towards negative u (`border_col_lo`), positive u, negative / positive v.
  bool border_col_lo = false, border_col_hi = false, border_row_lo = false, border_row_hi = false;
  double border_extent = 0.5;
};

// Fits the corner from init.px with the pixels of its window (init.extent_*; false when that
// window needs more than FastFitScratch::kMaxHalf - 1 px each side). Fills `out` as fit_saddle_fast does (px,
// contrast = |b|, rms, weight, position_var_per_noise, shading, undistorted); sigma is left 0 (the model has
// none) and out.harmonic is set. False when the window does not fit, the fit diverges or it moved to another
// lattice point (more than 0.35 of a step from the start: the model repeats with the grid).
bool fit_sine_corner(const LumaView& img, const CameraModel& cam, const UndistortMap& map,
                     const SineInit& init, int max_iterations, double tolerance_px, FastFitScratch& work,
                     SaddleFit& out);

}  // namespace naneye::recon
