#pragma once
// The per-frame saddle fit of the corner detector, in float with vectorised inner loops (SSE2 or
// AVX2, recon/corners/simd.hpp) and the window's undistorted coordinates read from a per-camera
// UndistortMap. Same model
// as fit_saddle (corners/refine.hpp):
//   I = a + g . d + (b + h . d) * erf(u1 / (sqrt2 s)) * erf(u2 / (sqrt2 s)),  u_k = n_k . (y - q)
// in two variants:
// - full: all 11 parameters (corner, both edge normals, blur, six shading terms);
// - fixed edges: the edge normals are given (from the grid itself: the board's edges through a
//   corner are the straight lines through its neighbours on the undistorted plane), only the
//   corner, the blur and the six linear shading terms are fitted (9 parameters).
#include <Eigen/Core>
#include <array>

#include "naneye/recon/camera/camera_model.hpp"
#include "naneye/recon/camera/undistort_map.hpp"
#include "naneye/recon/corners/refine.hpp"

namespace naneye::recon {

// Directions of the two edges through a corner (tangents, not normals): on the undistorted
// normalized plane when `normalized_ok`, and in raw pixels (used for windows beyond the fold).
struct EdgeDirections {
  Eigen::Vector2d row_n{1, 0}, col_n{0, 1};    // along the grid row / column, normalized plane
  Eigen::Vector2d row_px{1, 0}, col_px{0, 1};  // the same in raw pixels
  bool normalized_ok = false;
  // Distance (raw px) from the corner to the next grid line parallel to the row edge and to the
  // column edge: the window keeps those lines and their blur out (0: not known).
  double row_line_px = 0, col_line_px = 0;
};

// Work space of one fit (~50 KB): owned by the caller and reused, so a fit allocates nothing.
struct FastFitScratch {
  static constexpr int kMaxHalf = 9;      // window half size incl. the taper: radius <= 8
  static constexpr int kMaxPixels = 368;  // (2 * 9 + 1)^2 = 361, rounded up to whole 8-float vectors
  using Arr = Eigen::Array<float, Eigen::Dynamic, 1, 0, kMaxPixels, 1>;
  Arr dx, dy, yx, yy, val, wt;  // the window: offsets / half, local coordinates, pixel values, weights
  Arr r, E1, E2, G1, G2, S, U1, U2;
  std::array<Arr, 11> J, Jw;  // Jacobian columns and their weighted copies
  // The fit's innermost loops 8 floats at a time (AVX2 + FMA) when this CPU has them, else 4
  // (SSE2); tests turn it off to compare both.
  bool use_avx2 = false;
  FastFitScratch();  // sizes every array to kMaxPixels (fixed storage: no heap), picks the kernels
};

// A fit's window, as load_fit_window leaves it in the work space: n pixels (dx, dy their offsets
// from the centre pixel (cx, cy) over `half`; yx, yy their local undistorted coordinates y = Jp
// (x(p) - x0), x0 the centre's undistorted coordinates; val, wt their values and weights, the
// weights zero beyond n up to a whole 8-float vector). `off` is the start px - centre.
struct FitWindow {
  int n = 0, cx = 0, cy = 0, half = 0;
  bool undistorted = false;  // false: beyond the model's fold, y are raw pixel offsets
  Eigen::Vector2d x0{0, 0}, off{0, 0};
  Eigen::Matrix2d Jp = Eigen::Matrix2d::Identity();
};

// Loads the pixels within `radius` (Chebyshev, from px; a 1 px linear taper beyond) into `w`.
// False when the window does not fit in the usable area or exceeds the work space.
bool load_fit_window(const LumaView& img, const CameraModel& cam, const UndistortMap& map,
                     const Eigen::Vector2d& px, double radius, FastFitScratch& w, FitWindow& win);

// A fit's last step: the corner q (local coordinates of `win`) back to raw pixels in out.px, and the
// linear terms lin = (a, gx, gy, b, hx, hy), gradients per window half size at the window's centre,
// referred to that corner with gradients per raw pixel in out.shading.
void place_corner(const FitWindow& win, const CameraModel& cam, const Eigen::Vector2d& q, const double* lin,
                  SaddleFit& out);

// Fits one corner from init.px with the pixels within `radius` (Chebyshev, 1 px taper beyond), like
// fit_saddle. With `edges` non-null the edge normals are fixed to those directions (mapped to the
// window's local coordinates) and init.theta1/theta2 are ignored; otherwise all 11 parameters are
// fitted. Returns false when the window does not fit in the usable area or the fit diverges.
bool fit_saddle_fast(const LumaView& img, const CameraModel& cam, const UndistortMap& map,
                     const SaddleInit& init, const EdgeDirections* edges, double radius, int max_iterations,
                     double tolerance_px, FastFitScratch& work, SaddleFit& out);

}  // namespace naneye::recon
