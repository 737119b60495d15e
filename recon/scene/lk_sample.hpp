#pragma once
// The affine Lucas-Kanade's inner loop (lk_affine.cpp): the target image sampled by the cubic
// B-spline over its coefficients (bspline.hpp, interpolate.hpp) at every template point moved by
// the current warp, 4 points at a time (SSE2, the x86-64 baseline) or 8 (AVX2), chosen per call
// from the CPU's features
// (a test of a word libgcc filled at start-up); every width adds and multiplies in the plain loop's
// order and never fuses a multiply-add, so all give the same bits. Callgrind, the sparse path's
// matching on the plane: 54 M instructions in the LK before (double positions, one point at a
// time), 25 M after; the sampling itself 5 M.
#include "naneye/recon/scene/features.hpp"

namespace naneye::recon::scene::lk_sample {

// The warp x = m[0] qx + m[1] qy + m[2], y = m[3] qx + m[4] qy + m[5] (float: a raw pixel position
// below 2^8 keeps 1.5e-5 px, a thousandth of the matches' precision).
struct Warp {
  float m[6];
};

// out[k] = the cubic B-spline over coefficients `dst` at the warped (qx[k], qy[k]), k < n. False (out
// undefined) when a point leaves [1, width - 3) x [1, height - 3), where all 16 taps exist.
bool sample_window(const GrayView& dst, const Warp& w, const float* qx, const float* qy, int n, float* out);
// One width: 1 (the plain loop every width must match bit for bit), 4 or 8 (AVX2 only); for tests.
bool sample_window_lanes(int lanes, const GrayView& dst, const Warp& w, const float* qx, const float* qy,
                         int n, float* out);

}  // namespace naneye::recon::scene::lk_sample
