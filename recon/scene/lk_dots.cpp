// See lk_dots.hpp.
#include "lk_dots.hpp"

#include <immintrin.h>

#include <cassert>

#include "../corners/simd.hpp"

namespace naneye::recon::scene::lk_dots {
namespace {

constexpr int kMaxSums = kMaxArrays + 1;

void reduce(const float (*acc)[kBlock], int sums, double* out) {
  for (int j = 0; j < sums; ++j) {
    double s = 0;
    for (int l = 0; l < kBlock; ++l) s += static_cast<double>(acc[j][l]);
    out[j] = s;
  }
}

void dot_plain(const float* a, float c, const float* const* b, int m, int n8, double* out) {
  float acc[kMaxSums][kBlock] = {};
  for (int k = 0; k < n8; k += kBlock)
    for (int l = 0; l < kBlock; ++l) {
      const float x = a[k + l] - c;
      acc[0][l] += x * x;
      for (int j = 0; j < m; ++j) acc[1 + j][l] += x * b[j][k + l];
    }
  reduce(acc, m + 1, out);
}

// M known at compile time and the loop over it unrolled, so that the M + 1 accumulators stay in
// registers (otherwise GCC keeps them on the stack: a load and a store per product).
template <int M>
NANEYE_SIMD_INLINE void dot_sse_m(const float* a, float c, const float* const* b, int n8, double* out) {
  using simd::V4;
  V4 lo[M + 1] = {}, hi[M + 1] = {};
  for (int k = 0; k < n8; k += kBlock) {
    const V4 a0 = simd::load<V4>(a + k) - c, a1 = simd::load<V4>(a + k + 4) - c;
    lo[0] += a0 * a0;
    hi[0] += a1 * a1;
#pragma GCC unroll 16
    for (int j = 0; j < M; ++j) {
      lo[1 + j] += a0 * simd::load<V4>(b[j] + k);
      hi[1 + j] += a1 * simd::load<V4>(b[j] + k + 4);
    }
  }
  float acc[kMaxSums][kBlock];
  for (int j = 0; j <= M; ++j) {
    simd::store(acc[j], lo[j]);
    simd::store(acc[j] + 4, hi[j]);
  }
  reduce(acc, M + 1, out);
}

// "avx2" without "fma": a fused multiply-add would round once where the others round twice.
template <int M>
__attribute__((target("avx2"))) NANEYE_SIMD_INLINE void dot_avx2_m(const float* a, float c,
                                                                   const float* const* b, int n8,
                                                                   double* out) {
  const __m256 cv = _mm256_set1_ps(c);
  __m256 acc8[M + 1];
  for (int j = 0; j <= M; ++j) acc8[j] = _mm256_setzero_ps();
  for (int k = 0; k < n8; k += kBlock) {
    const __m256 av = _mm256_sub_ps(_mm256_loadu_ps(a + k), cv);
    acc8[0] = _mm256_add_ps(acc8[0], _mm256_mul_ps(av, av));
#pragma GCC unroll 16
    for (int j = 0; j < M; ++j)
      acc8[1 + j] = _mm256_add_ps(acc8[1 + j], _mm256_mul_ps(av, _mm256_loadu_ps(b[j] + k)));
  }
  float acc[kMaxSums][kBlock];
  for (int j = 0; j <= M; ++j) _mm256_storeu_ps(acc[j], acc8[j]);
  reduce(acc, M + 1, out);
}

#define NANEYE_DOT_CASES(kernel)          \
  switch (m) {                            \
    case 0:                               \
      return kernel<0>(a, c, b, n8, out); \
    case 1:                               \
      return kernel<1>(a, c, b, n8, out); \
    case 2:                               \
      return kernel<2>(a, c, b, n8, out); \
    case 3:                               \
      return kernel<3>(a, c, b, n8, out); \
    case 4:                               \
      return kernel<4>(a, c, b, n8, out); \
    case 5:                               \
      return kernel<5>(a, c, b, n8, out); \
    case 6:                               \
      return kernel<6>(a, c, b, n8, out); \
    case 7:                               \
      return kernel<7>(a, c, b, n8, out); \
    case 8:                               \
      return kernel<8>(a, c, b, n8, out); \
    case 9:                               \
      return kernel<9>(a, c, b, n8, out); \
    default:                              \
      return;                             \
  }

void dot_sse(const float* a, float c, const float* const* b, int m, int n8, double* out) {
  NANEYE_DOT_CASES(dot_sse_m)
}

__attribute__((target("avx2"))) void dot_avx2(const float* a, float c, const float* const* b, int m, int n8,
                                              double* out) {
  NANEYE_DOT_CASES(dot_avx2_m)
}
#undef NANEYE_DOT_CASES

}  // namespace

void dot_many(const float* a, float c, const float* const* b, int m, int n8, double* out) {
  assert(m >= 0 && m <= kMaxArrays && n8 % kBlock == 0);
  (simd::has_avx2() ? dot_avx2 : dot_sse)(a, c, b, m, n8, out);
}

void dot_many_lanes(int lanes, const float* a, float c, const float* const* b, int m, int n8, double* out) {
  assert(m >= 0 && m <= kMaxArrays && n8 % kBlock == 0);
  if (lanes == 8) return dot_avx2(a, c, b, m, n8, out);
  if (lanes == 4) return dot_sse(a, c, b, m, n8, out);
  dot_plain(a, c, b, m, n8, out);
}

}  // namespace naneye::recon::scene::lk_dots
