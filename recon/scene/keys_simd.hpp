#pragma once
// Keys' cubic convolution weights (interpolate.hpp's keys_weights) on whole vectors: the same
// expressions in the same order, so every width gives the scalar weights to the bit (no fused
// multiply-add: the AVX2 functions are compiled for "avx2" alone, and ISO C++ mode does not contract).
// Shared by the LK's sampling (lk_sample.cpp) and the dense path's rectification (resample_kernels.cpp).
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

}  // namespace naneye::recon::scene
