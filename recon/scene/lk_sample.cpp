// See lk_sample.hpp. The 4-lane path is GCC vector code over corners/simd.hpp's helpers, the 8-lane
// one AVX2 intrinsics (cubic_simd.hpp's AVX2 taps cannot be inlined into width-generic code compiled
// for the baseline).
#include "lk_sample.hpp"

#include <immintrin.h>

#include "../corners/simd.hpp"
#include "cubic_simd.hpp"
#include "interpolate.hpp"

namespace naneye::recon::scene::lk_sample {
namespace {
using simd::kLanes;
using simd::load;
using simd::store;
using VI4 = int __attribute__((vector_size(16)));
template <class V>
using VInt = VI4;

// The plain loop over points [k0, n): the reference, and every width's tail. The bounds test is
// written as "inside" so that a NaN position (a degenerate warp) is outside too.
bool sample_plain(const GrayView& g, const Warp& w, const float* qx, const float* qy, int k0, int n,
                  float* out) {
  for (int k = k0; k < n; ++k) {
    const float x = w.m[0] * qx[k] + w.m[1] * qy[k] + w.m[2], y = w.m[3] * qx[k] + w.m[4] * qy[k] + w.m[5];
    if (!(x >= 1 && y >= 1 && x < g.width - 3 && y < g.height - 3)) return false;
    out[k] = sample_bspline(g, x, y);
  }
  return true;
}

template <class V>
NANEYE_SIMD_INLINE bool sample_v(const GrayView& g, const Warp& w, const float* qx, const float* qy, int n,
                                 float* out) {
  constexpr int L = kLanes<V>;
  using I = VInt<V>;
  const V m0 = (V{} + w.m[0]), m1 = (V{} + w.m[1]), m2 = (V{} + w.m[2]);
  const V m3 = (V{} + w.m[3]), m4 = (V{} + w.m[4]), m5 = (V{} + w.m[5]);
  const V lo = (V{} + 1.0f), hx = V{} + static_cast<float>(g.width - 3),
          hy = V{} + static_cast<float>(g.height - 3);
  int k = 0;
  for (; k + L <= n; k += L) {
    const V a = load<V>(qx + k), b = load<V>(qy + k);
    const V x = m0 * a + m1 * b + m2, y = m3 * a + m4 * b + m5;
    // Written as "inside" so that a NaN position (a degenerate warp) is outside too.
    const auto inside = (x >= lo) & (y >= lo) & (x < hx) & (y < hy);
    for (int l = 0; l < L; ++l)
      if (!inside[l]) return false;
    const I c = __builtin_convertvector(x, I), r = __builtin_convertvector(y, I);
    V wx[4], wy[4];
    bspline_v<V>(x - __builtin_convertvector(c, V), wx);
    bspline_v<V>(y - __builtin_convertvector(r, V), wy);
    const I idx = (r - 1) * (I{} + g.width) + (c - 1);
    store(out + k, cubic_from_taps_v<V>(g.data, idx, g.width, wx, wy));
  }
  return sample_plain(g, w, qx, qy, k, n, out);
}

bool sample_sse(const GrayView& g, const Warp& w, const float* qx, const float* qy, int n, float* out) {
  return sample_v<simd::V4>(g, w, qx, qy, n, out);
}
// The same in AVX2 intrinsics (callgrind: 83 instructions per point with lane-by-lane loads), the taps
// read row by row (cubic_from_taps8). The same operations in the same order as sample_v.
__attribute__((target("avx2"))) bool sample_avx2(const GrayView& g, const Warp& w, const float* qx,
                                                 const float* qy, int n, float* out) {
  const __m256 m0 = _mm256_set1_ps(w.m[0]), m1 = _mm256_set1_ps(w.m[1]), m2 = _mm256_set1_ps(w.m[2]);
  const __m256 m3 = _mm256_set1_ps(w.m[3]), m4 = _mm256_set1_ps(w.m[4]), m5 = _mm256_set1_ps(w.m[5]);
  const __m256 lo = _mm256_set1_ps(1.0f), hx = _mm256_set1_ps(static_cast<float>(g.width - 3)),
               hy = _mm256_set1_ps(static_cast<float>(g.height - 3));
  const __m256i width = _mm256_set1_epi32(g.width), one = _mm256_set1_epi32(1);
  int k = 0;
  for (; k + 8 <= n; k += 8) {
    const __m256 a = _mm256_loadu_ps(qx + k), b = _mm256_loadu_ps(qy + k);
    const __m256 x = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(m0, a), _mm256_mul_ps(m1, b)), m2);
    const __m256 y = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(m3, a), _mm256_mul_ps(m4, b)), m5);
    // Ordered comparisons: false for NaN, so a degenerate warp is outside.
    const __m256 inside =
        _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(x, lo, _CMP_GE_OQ), _mm256_cmp_ps(y, lo, _CMP_GE_OQ)),
                      _mm256_and_ps(_mm256_cmp_ps(x, hx, _CMP_LT_OQ), _mm256_cmp_ps(y, hy, _CMP_LT_OQ)));
    if (_mm256_movemask_ps(inside) != 0xff) return false;
    const __m256i c = _mm256_cvttps_epi32(x), r = _mm256_cvttps_epi32(y);
    __m256 wx[4], wy[4];
    bspline8(_mm256_sub_ps(x, _mm256_cvtepi32_ps(c)), wx);
    bspline8(_mm256_sub_ps(y, _mm256_cvtepi32_ps(r)), wy);
    const __m256i idx =
        _mm256_add_epi32(_mm256_mullo_epi32(_mm256_sub_epi32(r, one), width), _mm256_sub_epi32(c, one));
    _mm256_storeu_ps(out + k, cubic_from_taps8(g.data, idx, g.width, wx, wy));
  }
  return sample_plain(g, w, qx, qy, k, n, out);
}
}  // namespace

bool sample_window(const GrayView& dst, const Warp& w, const float* qx, const float* qy, int n, float* out) {
  return (simd::has_avx2() ? sample_avx2 : sample_sse)(dst, w, qx, qy, n, out);
}

bool sample_window_lanes(int lanes, const GrayView& dst, const Warp& w, const float* qx, const float* qy,
                         int n, float* out) {
  if (lanes == 8) return sample_avx2(dst, w, qx, qy, n, out);
  if (lanes == 4) return sample_sse(dst, w, qx, qy, n, out);
  return sample_plain(dst, w, qx, qy, 0, n, out);
}

}  // namespace naneye::recon::scene::lk_sample
