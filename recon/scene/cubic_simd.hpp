#pragma once
// The cubic kernels of interpolate.hpp (Keys' convolution and the cubic B-spline's weights, and
// cubic_from_taps) on whole vectors: the same expressions in the same order, so every width gives the scalar
// results to the bit (no fused multiply-add: the AVX2 functions are compiled for "avx2" alone, and ISO C++
// mode does not contract). The LK's sampling (lk_sample.cpp) uses the B-spline, the dense path's
// rectification (resample_kernels.cpp) Keys.
#include <immintrin.h>

#include <cstddef>

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

// Four floats from lo and four from hi, as one vector.
__attribute__((target("avx2"))) NANEYE_SIMD_INLINE __m256 load_halves(const float* lo, const float* hi) {
  return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(lo)), _mm_loadu_ps(hi), 1);
}

// The same in AVX2. Each point's 4 x 4 taps are 4 runs of 4 floats: read as one 4-float load per
// point and row and transposed into one vector per tap column, 32 loads and 32 shuffles per 8
// points. AVX2's gather (16 per 8 points, 128 single-float loads) took 1.7x the time (a 21 x 21 LK
// window: 2.14 against 1.23 us, bench_lk's BM_LkSampleWindow; docs/scene.md).
__attribute__((target("avx2"))) NANEYE_SIMD_INLINE __m256 cubic_from_taps8(const float* base, __m256i idx,
                                                                           int width, const __m256* wx,
                                                                           const __m256* wy) {
  alignas(32) int at[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(at), idx);
  __m256 acc = _mm256_setzero_ps();
  for (int i = 0; i < 4; ++i) {
    const std::ptrdiff_t off = static_cast<std::ptrdiff_t>(i) * width;
    // Point l's row in the low half, point l + 4's in the high half.
    const float* row0 = base + off;
    const __m256 a0 = load_halves(row0 + at[0], row0 + at[4]), a1 = load_halves(row0 + at[1], row0 + at[5]),
                 a2 = load_halves(row0 + at[2], row0 + at[6]), a3 = load_halves(row0 + at[3], row0 + at[7]);
    const __m256 t0 = _mm256_unpacklo_ps(a0, a1), t1 = _mm256_unpackhi_ps(a0, a1);
    const __m256 t2 = _mm256_unpacklo_ps(a2, a3), t3 = _mm256_unpackhi_ps(a2, a3);
    const __m256 p0 = _mm256_shuffle_ps(t0, t2, 0x44), p1 = _mm256_shuffle_ps(t0, t2, 0xEE);
    const __m256 p2 = _mm256_shuffle_ps(t1, t3, 0x44), p3 = _mm256_shuffle_ps(t1, t3, 0xEE);
    const __m256 row =
        _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(wx[0], p0), _mm256_mul_ps(wx[1], p1)),
                                    _mm256_mul_ps(wx[2], p2)),
                      _mm256_mul_ps(wx[3], p3));
    acc = _mm256_add_ps(acc, _mm256_mul_ps(wy[i], row));
  }
  return acc;
}

}  // namespace naneye::recon::scene
