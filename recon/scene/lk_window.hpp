#pragma once
// The affine LK's window algebra (lk_affine.cpp): the float arrays of a fit's window (its
// steepest-descent images, their projections, the curvature gain's monomials) and their Gram
// matrices, plain and under the pair's 3 x 3 noise kernel. Only lk_affine.cpp includes it; apart
// so that the fit reads as the method, these as the arithmetic under it.
#include <Eigen/Core>
#include <array>

#include "../corners/simd.hpp"
#include "lk_dots.hpp"
#include "naneye/recon/scene/lk_affine.hpp"

namespace naneye::recon::scene::lk_window {

// The widest window refine_affine takes. It was 15 x 15 (radius 7) until 2026-12-06, and a
// SparseSettings::wide_radius of 8 or more then gave the narrow window alone, silently.
inline constexpr int kMaxSide = 2 * kMaxLkRadius + 1;
inline constexpr int kMaxN = kMaxSide * kMaxSide;
inline constexpr int kMaxN8 = lk_dots::padded(kMaxN);
// The grown window's rows (side + 2 columns) at a stride of whole 4-float vectors.
inline constexpr int kMaxStride = (kMaxSide + 2 + 3) / 4 * 4,
                     kMaxGrown8 = lk_dots::padded((kMaxSide + 2) * kMaxStride);

// sum_k v_i[k] v_j[k] over n8 floats (zero beyond the data): the triangle as dot products, mirrored.
template <int K>
Eigen::Matrix<double, K, K> dot_gram(const float* const (&v)[K], int n8) {
  Eigen::Matrix<double, K, K> out;
  double row[K];
  for (int i = 0; i < K; ++i) {
    lk_dots::dot_many(v[i], 0.f, v + i + 1, K - 1 - i, n8, row);
    for (int j = i; j < K; ++j) out(i, j) = out(j, i) = row[j - i];
  }
  return out;
}

// sum_p (b * v)_p (b * v)_p^T over the window grown by one pixel (the kernel's reach) for the
// K-vectors v = (v_0, .., v_K-1) per pixel of the side x side window (zero outside it), each v_i an
// image over the window, row-major: the noise of weighted sums of the pixels under the pair's 3 x 3
// noise kernel b. Float 4-vectors along the rows over zero-padded copies (a covariance needs no more
// than float's 1e-7).
template <int K>
Eigen::Matrix<double, K, K> kernel_gram(const std::array<float, 9>& b, const float* const (&v)[K], int side) {
  using simd::V4;
  const int g = side + 2, stride = (g + 3) / 4 * 4, in_stride = stride + 4;
  const int n8 = lk_dots::padded(g * stride);
  // Each input at (2, 2) of a zero plane of side + 4 rows: out(r, c) = sum b(i, j) in(r + i, c + j).
  alignas(16) float pad[(kMaxSide + 4) * (kMaxStride + 4)] = {};
  alignas(32) float f[K][kMaxGrown8];
  // The kernel in registers: read through the reference, b might alias the planes for all the compiler
  // knows, and it reloaded and re-splatted every tap (~30 % of the Bayer sparse path in callgrind).
  V4 bk[9];
  for (int i = 0; i < 9; ++i) bk[i] = simd::splat<V4>(b[static_cast<std::size_t>(i)]);
  for (int e = 0; e < K; ++e) {
    for (int r = 0; r < side; ++r)
      for (int c = 0; c < side; ++c) pad[(r + 2) * in_stride + c + 2] = v[e][r * side + c];
    for (int r = 0; r < g; ++r) {
      const float* p0 = &pad[r * in_stride];
      const float* p1 = p0 + in_stride;
      const float* p2 = p1 + in_stride;
      for (int c = 0; c < stride; c += 4) {  // columns >= g read only the zero padding: stay 0
        // The taps rows first, then columns, from a zero start: a plain loop over (i, j)'s order and bits.
        V4 acc = V4{};
        acc += bk[0] * simd::load<V4>(p0 + c);
        acc += bk[1] * simd::load<V4>(p0 + c + 1);
        acc += bk[2] * simd::load<V4>(p0 + c + 2);
        acc += bk[3] * simd::load<V4>(p1 + c);
        acc += bk[4] * simd::load<V4>(p1 + c + 1);
        acc += bk[5] * simd::load<V4>(p1 + c + 2);
        acc += bk[6] * simd::load<V4>(p2 + c);
        acc += bk[7] * simd::load<V4>(p2 + c + 1);
        acc += bk[8] * simd::load<V4>(p2 + c + 2);
        simd::store(&f[e][r * stride + c], acc);
      }
    }
    for (int k = g * stride; k < n8; ++k) f[e][k] = 0.f;
  }
  const float* filtered[K];
  for (int e = 0; e < K; ++e) filtered[e] = f[e];
  return dot_gram<K>(filtered, n8);
}

// The translation's noise: kernel_gram over the steepest-descent vectors projected onto it first
// (P B P^T = the same sum over P sd), 2 filtered images, not 6.
inline Eigen::Matrix2d kernel_outer(const std::array<float, 9>& b, const float* x, const float* y, int side) {
  const float* const v[2] = {x, y};
  return kernel_gram<2>(b, v, side);
}

// p = P sd per pixel (P a 2 x 6 projection) as two float arrays over whole blocks of the padded
// window, written or (accumulate) added to px, py.
inline void project(const Eigen::Matrix<double, 2, 6>& P, const float (&sd)[6][kMaxN8], int n8, float* px,
                    float* py, bool accumulate = false) {
  using simd::V4;
  // P's rows as float splats once (in the loop the compiler converted and splatted them at every step).
  V4 p0[6], p1[6];
  for (int j = 0; j < 6; ++j) {
    p0[j] = simd::splat<V4>(static_cast<float>(P(0, j)));
    p1[j] = simd::splat<V4>(static_cast<float>(P(1, j)));
  }
  for (int k = 0; k < n8; k += 4) {
    V4 a = accumulate ? simd::load<V4>(px + k) : V4{}, c = accumulate ? simd::load<V4>(py + k) : V4{};
    for (int j = 0; j < 6; ++j) {
      const V4 v = simd::load<V4>(&sd[j][k]);
      a += p0[j] * v;
      c += p1[j] * v;
    }
    simd::store(px + k, a);
    simd::store(py + k, c);
  }
}

// out[k] = a[k] b[k] over whole blocks (n8: lk_dots::padded). In vectors: at -O2 GCC's very cheap
// cost model left these loops scalar (their count is not known to be a whole number of vectors),
// 27 % of a 21 x 21 fit's own time (bench_lk).
inline void multiply(const float* a, const float* b, int n8, float* out) {
  using simd::V4;
  for (int k = 0; k < n8; k += 4) simd::store(out + k, simd::load<V4>(a + k) * simd::load<V4>(b + k));
}

// The curvature gain's monomials over a window of this radius, row-major, 0 beyond its n points:
// 1/2 dc^2, dc dr, 1/2 dr^2 (a table per radius, made once).
inline const float (&monomials(int rad))[3][kMaxN8] {
  struct Table {
    alignas(32) float m[kMaxLkRadius + 1][3][kMaxN8] = {};
    Table() {
      for (int r = 0; r <= kMaxLkRadius; ++r)
        for (int dr = -r, k = 0; dr <= r; ++dr)
          for (int dc = -r; dc <= r; ++dc, ++k) {
            m[r][0][k] = 0.5f * static_cast<float>(dc * dc);
            m[r][1][k] = static_cast<float>(dc * dr);
            m[r][2][k] = 0.5f * static_cast<float>(dr * dr);
          }
    }
  };
  static const Table table;
  return table.m[rad];
}

// H(i, j) = sum_k a_i[k] b_j[k] for j >= i, mirrored: the 21 distinct entries as dot products.
// a_i is b_i itself or b_i on a subset of the pixels (0 elsewhere): then a_i b_i = a_i^2.
inline Eigen::Matrix<double, 6, 6> gram(const float (&a)[6][kMaxN8], const float (&b)[6][kMaxN8], int n8) {
  Eigen::Matrix<double, 6, 6> H;
  double row[6];
  for (int i = 0; i < 6; ++i) {
    const float* bs[5];
    for (int j = i + 1; j < 6; ++j) bs[j - i - 1] = b[j];
    lk_dots::dot_many(a[i], 0.f, bs, 5 - i, n8, row);
    for (int j = i; j < 6; ++j) H(i, j) = H(j, i) = row[j - i];
  }
  return H;
}

}  // namespace naneye::recon::scene::lk_window
