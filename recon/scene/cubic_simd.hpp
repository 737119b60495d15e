#pragma once
// The cubic kernels of interpolate.hpp (Keys' convolution and the cubic B-spline's weights, and
// cubic_from_taps) on whole vectors: the same expressions in the same order, so every width gives the scalar
// results to the bit (no fused multiply-add: the AVX2 functions are compiled for "avx2" alone, and ISO C++
// mode does not contract). The LK's sampling (lk_sample.cpp) uses the B-spline, the dense path's
// rectification (resample_kernels.cpp) Keys.
#include <immintrin.h>

#include "../corners/simd.hpp"

namespace naneye::recon::scene {

// keys_weights() per lane, the same expressions in the same order.
template <class V>
NANEYE_SIMD_INLINE void keys_v(V t, V w[4]) {
  const V t2 = t * t, t3 = t2 * t;
  w[0] = (V{} + -0.5f) * t3 + t2 - (V{} + 0.5f) * t;
  w[1] = (V{} + 1.5f) * t3 - (V{} + 2.5f) * t2 + (V{} + 1.0f);
  w[2] = (V{} + -1.5f) * t3 + (V{} + 2.0f) * t2 + (V{} + 0.5f) * t;
  w[3] = (V{} + 0.5f) * t3 - (V{} + 0.5f) * t2;
}

// keys_weights() in AVX2, the same expressions in the same order.
__attribute__((target("avx2"))) NANEYE_SIMD_INLINE void keys8(__m256 t, __m256* k) {
  const __m256 t2 = _mm256_mul_ps(t, t), t3 = _mm256_mul_ps(t2, t);
  k[0] = _mm256_sub_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(-0.5f), t3), t2),
                       _mm256_mul_ps(_mm256_set1_ps(0.5f), t));
  k[1] = _mm256_add_ps(
      _mm256_sub_ps(_mm256_mul_ps(_mm256_set1_ps(1.5f), t3), _mm256_mul_ps(_mm256_set1_ps(2.5f), t2)),
      _mm256_set1_ps(1.0f));
  k[2] = _mm256_add_ps(
      _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(-1.5f), t3), _mm256_mul_ps(_mm256_set1_ps(2.0f), t2)),
      _mm256_mul_ps(_mm256_set1_ps(0.5f), t));
  k[3] = _mm256_sub_ps(_mm256_mul_ps(_mm256_set1_ps(0.5f), t3), _mm256_mul_ps(_mm256_set1_ps(0.5f), t2));
}
// bspline_weights() per lane.
template <class V>
NANEYE_SIMD_INLINE void bspline_v(V t, V w[4]) {
  const V t2 = t * t, t3 = t2 * t, s = (V{} + 1.0f) - t;
  w[0] = (V{} + 1.0f / 6.0f) * (s * s * s);
  w[1] = (V{} + 0.5f) * t3 - t2 + (V{} + 2.0f / 3.0f);
  w[2] = (V{} + -0.5f) * t3 + (V{} + 0.5f) * t2 + (V{} + 0.5f) * t + (V{} + 1.0f / 6.0f);
  w[3] = (V{} + 1.0f / 6.0f) * t3;
}

// bspline_weights() in AVX2.
__attribute__((target("avx2"))) NANEYE_SIMD_INLINE void bspline8(__m256 t, __m256* k) {
  const __m256 t2 = _mm256_mul_ps(t, t), t3 = _mm256_mul_ps(t2, t),
               s = _mm256_sub_ps(_mm256_set1_ps(1.0f), t);
  const __m256 sixth = _mm256_set1_ps(1.0f / 6.0f), half = _mm256_set1_ps(0.5f);
  k[0] = _mm256_mul_ps(sixth, _mm256_mul_ps(_mm256_mul_ps(s, s), s));
  k[1] = _mm256_add_ps(_mm256_sub_ps(_mm256_mul_ps(half, t3), t2), _mm256_set1_ps(2.0f / 3.0f));
  k[2] = _mm256_add_ps(
      _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(-0.5f), t3), _mm256_mul_ps(half, t2)),
                    _mm256_mul_ps(half, t)),
      sixth);
  k[3] = _mm256_mul_ps(sixth, t3);
}

// base[idx] per lane.
template <class V, class I>
NANEYE_SIMD_INLINE void gather(const float* base, const I& idx, V& v) {
  for (int l = 0; l < simd::kLanes<V>; ++l) v[l] = base[idx[l]];
}

// cubic_from_taps per lane: the 4 x 4 taps from base[idx] (their top-left, rows `width` apart).
template <class V, class I>
NANEYE_SIMD_INLINE V cubic_from_taps_v(const float* base, I idx, int width, const V wx[4], const V wy[4]) {
  V acc = V{} + 0.f;
  for (int i = 0; i < 4; ++i, idx += width) {
    V p0, p1, p2, p3;
    gather<V>(base, idx, p0);
    gather<V>(base, idx + 1, p1);
    gather<V>(base, idx + 2, p2);
    gather<V>(base, idx + 3, p3);
    acc += wy[i] * (wx[0] * p0 + wx[1] * p1 + wx[2] * p2 + wx[3] * p3);
  }
  return acc;
}

// The same in AVX2 with its gather instruction (16 gathers per 8 points, where lane-by-lane loads
// took 128 loads and inserts).
__attribute__((target("avx2"))) NANEYE_SIMD_INLINE __m256 cubic_from_taps8(const float* base, __m256i idx,
                                                                           int width, const __m256* wx,
                                                                           const __m256* wy) {
  const __m256i step = _mm256_set1_epi32(width);
  __m256 acc = _mm256_setzero_ps();
  for (int i = 0; i < 4; ++i, idx = _mm256_add_epi32(idx, step)) {
    const __m256 p0 = _mm256_i32gather_ps(base, idx, 4);
    const __m256 p1 = _mm256_i32gather_ps(base + 1, idx, 4);
    const __m256 p2 = _mm256_i32gather_ps(base + 2, idx, 4);
    const __m256 p3 = _mm256_i32gather_ps(base + 3, idx, 4);
    const __m256 row =
        _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(wx[0], p0), _mm256_mul_ps(wx[1], p1)),
                                    _mm256_mul_ps(wx[2], p2)),
                      _mm256_mul_ps(wx[3], p3));
    acc = _mm256_add_ps(acc, _mm256_mul_ps(wy[i], row));
  }
  return acc;
}

}  // namespace naneye::recon::scene
