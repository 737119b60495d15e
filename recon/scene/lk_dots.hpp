#pragma once
// The affine LK's sums (lk_affine.cpp) as dot products of float arrays: one array a, taken about a
// centre c, against itself and several others: sum (a - c)^2 and sum (a - c) b_j. 8 float partial
// sums per output (one per k mod 8) reduced in double in lane order; the plain loop, SSE2 (two
// 4-lane vectors) and AVX2 (one 8-lane vector, no fused multiply-add) add and multiply in that same
// order, so all three give the same bits (LkDots.*). Float: a window of <= 441 products in 8 partial
// sums carries ~1e-6 relative error, far below what a Hessian or a Gauss-Newton step needs; the
// centre keeps a window's variance from cancelling (lk_affine.cpp). They replaced double outer
// products and sums: callgrind, the sparse path on the plane, 125.6 -> 107.4 M instructions per
// pair (docs/scene.md, "Sparse speed").
#include <cstddef>

namespace naneye::recon::scene::lk_dots {

inline constexpr int kBlock = 8;      // arrays hold a multiple of this many floats, zero beyond n
inline constexpr int kMaxArrays = 9;  // b arrays per call

constexpr int padded(int n) {
  return (n + kBlock - 1) / kBlock * kBlock;
}

// out[0] = sum_{k < n8} (a[k] - c)^2, out[1 + j] = sum_{k < n8} (a[k] - c) b[j][k], j < m
// (m <= kMaxArrays); n8 a multiple of kBlock, the arrays zero (a: c) beyond the data. The centre is
// a float subtraction, exact for c = 0.
void dot_many(const float* a, float c, const float* const* b, int m, int n8, double* out);
// One width: 1 (the plain loop), 4 or 8 (AVX2 only); for tests.
void dot_many_lanes(int lanes, const float* a, float c, const float* const* b, int m, int n8, double* out);

}  // namespace naneye::recon::scene::lk_dots
