// The sub-pixel step's per-pixel fits and correlation() steps (dense_simd.hpp's fit_row, detail_row,
// update_row, mean_row, residual_row, centre_row, kappa_row): scalar loops or 4-float vectors for
// SSE2, and AVX2 builds computing 4 (in double) or 8 (in float) pixels at once, all with the same
// operations in the same order and every branch a select, so every build gives the plain loops' bits
// (tests/scene/test_dense_fit.cpp). Compiled for "avx2" alone: no fused multiply-add.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include <immintrin.h>

#include "dense_simd.hpp"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

namespace naneye::recon::scene::dense_simd {
namespace {

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

// The fit of pixel x, the plain loop the vector build must match.
inline void fit_one(const FitRow& r, int x) {
  const float N = r.s[0][x];
  r.n[x] = N;
  r.step[x] = 0;
  r.solved[x] = 0;
  if (!std::isfinite(r.d[x]) || r.m[x] == 0 || N < 4) {
    r.d[x] = kNan;
    return;
  }
  const double inv = 1.0 / N;
  const double sw = r.s[1][x], sl = r.s[2][x], sgr = r.s[3][x];
  const double Sww = r.s[4][x] - sw * sw * inv, Sgg = r.s[5][x] - sgr * sgr * inv;
  const double Swg = r.s[6][x] - sw * sgr * inv, Swl = r.s[7][x] - sw * sl * inv;
  const double Sgl = r.s[8][x] - sgr * sl * inv;
  const double det = Sww * Sgg - Swg * Swg;
  if (!(det > 0)) {
    r.d[x] = kNan;
    return;
  }
  const double a = (Sgg * Swl - Swg * Sgl) / det, c = (Swg * Swl - Sww * Sgl) / det;
  const double Sll = r.s[9][x] - sl * sl * inv;
  r.a[x] = static_cast<float>(a);
  r.c[x] = static_cast<float>(c);
  r.b[x] = static_cast<float>((sl - a * sw + c * sgr) * inv);
  r.s2[x] = static_cast<float>(std::max(0.0, Sll - a * Swl + c * Sgl) / std::max(1.0, N - 3.0));
  r.z[x] = static_cast<float>(Sww / det);
  r.sww[x] = static_cast<float>(Sww);
  r.swg[x] = static_cast<float>(Swg);
  r.sgg[x] = static_cast<float>(Sgg);
  if (!(a > 0)) return;  // anti-correlated: validate() refuses it
  // A Gauss-Newton step beyond half a pixel leaves the linearisation's range: clamp it. (G is the
  // left's gradient, a times the right's: c is the step itself, dense_subpixel.cpp.)
  r.step[x] = static_cast<float>(std::clamp(c, -0.5, 0.5));
  r.solved[x] = 1;
}

using VF = float __attribute__((vector_size(16)));
using VI = std::int32_t __attribute__((vector_size(16)));
using VD = double __attribute__((vector_size(32)));
using VL = std::int64_t __attribute__((vector_size(32)));
using V8 = float __attribute__((vector_size(32)));
using VI8 = std::int32_t __attribute__((vector_size(32)));

template <class T>
inline __attribute__((always_inline)) T ld(const float* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
template <class T>
inline __attribute__((always_inline)) void st(float* p, T v) {
  std::memcpy(p, &v, sizeof v);
}
// The conversions by their AVX2 instructions: GCC splits __builtin_convertvector of 4 floats to 4
// doubles into halves through the stack, and 64-bit masks to 32-bit ones into five shuffles.
#define NANEYE_AVX2_INLINE inline __attribute__((always_inline, target("avx2")))
NANEYE_AVX2_INLINE VD wide(VF v) {
  return _mm256_cvtps_pd(v);
}
NANEYE_AVX2_INLINE VF narrow(VD v) {
  return _mm256_cvtpd_ps(v);
}
// A double comparison's lanes (0 / -1 as 64 bits) as float lanes' (0 / -1 as 32 bits).
NANEYE_AVX2_INLINE VI lanes(VL m) {
  const __m256i even =
      _mm256_permutevar8x32_epi32(reinterpret_cast<__m256i>(m), _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6));
  return reinterpret_cast<VI>(_mm256_castsi256_si128(even));
}

// v as floats where the lane is not bad, else p's old values.
NANEYE_AVX2_INLINE void keep(float* p, VD v, int x, VI bad) {
  st(p + x, bad ? ld<VF>(p + x) : narrow(v));
}

// Pixels x .. x + 3: fit_one's expressions on doubles; where fit_one writes nothing, the old values
// are stored back.
NANEYE_AVX2_INLINE void fit4(const FitRow& r, int x) {
  const VF zero = VF{}, N = ld<VF>(r.s[0] + x), d = ld<VF>(r.d + x);
  st(r.n + x, N);
  // d - d is NaN unless d is finite; NaN compares unequal.
  const VI refused = (d - d != zero) | (ld<VF>(r.m + x) == zero) | (N < 4.f);
  const VD Nd = wide(N), inv = 1.0 / Nd;
  const VD sw = wide(ld<VF>(r.s[1] + x)), sl = wide(ld<VF>(r.s[2] + x)), sgr = wide(ld<VF>(r.s[3] + x));
  const VD Sww = wide(ld<VF>(r.s[4] + x)) - sw * sw * inv, Sgg = wide(ld<VF>(r.s[5] + x)) - sgr * sgr * inv;
  const VD Swg = wide(ld<VF>(r.s[6] + x)) - sw * sgr * inv, Swl = wide(ld<VF>(r.s[7] + x)) - sw * sl * inv;
  const VD Sgl = wide(ld<VF>(r.s[8] + x)) - sgr * sl * inv;
  const VD det = Sww * Sgg - Swg * Swg;
  const VI bad = refused | ~lanes(det > 0.0);
  st(r.d + x, bad ? VF{} + kNan : d);
  const VD a = (Sgg * Swl - Swg * Sgl) / det, c = (Swg * Swl - Sww * Sgl) / det;
  const VD Sll = wide(ld<VF>(r.s[9] + x)) - sl * sl * inv;
  const VD res = Sll - a * Swl + c * Sgl, dof = Nd - 3.0;
  // std::max(lo, v) is v when lo < v, else lo; std::clamp(v, lo, hi) is lo when v < lo, else hi
  // when hi < v, else v: the same selects, NaN included.
  const VD s2 = (0.0 < res ? res : VD{} + 0.0) / (1.0 < dof ? dof : VD{} + 1.0);
  keep(r.a, a, x, bad);
  keep(r.c, c, x, bad);
  keep(r.b, (sl - a * sw + c * sgr) * inv, x, bad);
  keep(r.s2, s2, x, bad);
  keep(r.z, Sww / det, x, bad);
  keep(r.sww, Sww, x, bad);
  keep(r.swg, Swg, x, bad);
  keep(r.sgg, Sgg, x, bad);
  const VI ok = ~bad & lanes(a > 0.0);
  const VD q = c < -0.5 ? VD{} - 0.5 : 0.5 < c ? VD{} + 0.5 : c;
  st(r.step + x, ok ? narrow(q) : zero);
  st(r.solved + x, ok ? zero + 1.f : zero);
}

void fit_row_sse(const FitRow& r) {
  for (int x = r.lo; x < r.hi; ++x) fit_one(r, x);
}
// A local copy of the row's pointers: the kernels' stores (memcpy) could otherwise write them, and
// every one would be reloaded after each store.
__attribute__((target("avx2"))) void fit_row_avx2(const FitRow& row) {
  const FitRow r = row;
  int x = r.lo;
  for (; x + 4 <= r.hi; x += 4) fit4(r, x);
  for (; x < r.hi; ++x) fit_one(r, x);
}

inline void detail_one(const DetailRow& r, int x) {
  const double N = r.s[0][x];
  if (!(N >= 4)) {
    r.out[x] = 0.f;
    return;
  }
  const double inv = 1.0 / N;
  const double sw = r.s[1][x], sg = r.s[3][x];
  const double Sww = r.s[4][x] - sw * sw * inv, Sgg = r.s[5][x] - sg * sg * inv;
  const double Swg = r.s[6][x] - sw * sg * inv;
  const double det = Sww * Sgg - Swg * Swg;
  const double wgq_c = r.s[7][x] - sw * inv * r.sgq[x];
  const double ggq_c = r.s[8][x] - sg * inv * r.sgq[x];
  r.out[x] = det > 0 ? static_cast<float>((Sww * ggq_c - Swg * wgq_c) / det) : 0.f;
}
NANEYE_AVX2_INLINE void detail4(const DetailRow& r, int x) {
  const VD N = wide(ld<VF>(r.s[0] + x)), inv = 1.0 / N;
  const VD sw = wide(ld<VF>(r.s[1] + x)), sg = wide(ld<VF>(r.s[3] + x)), sgq = wide(ld<VF>(r.sgq + x));
  const VD Sww = wide(ld<VF>(r.s[4] + x)) - sw * sw * inv, Sgg = wide(ld<VF>(r.s[5] + x)) - sg * sg * inv;
  const VD Swg = wide(ld<VF>(r.s[6] + x)) - sw * sg * inv;
  const VD det = Sww * Sgg - Swg * Swg;
  const VD wgq_c = wide(ld<VF>(r.s[7] + x)) - sw * inv * sgq;
  const VD ggq_c = wide(ld<VF>(r.s[8] + x)) - sg * inv * sgq;
  const VI ok = lanes(N >= 4.0) & lanes(det > 0.0);
  st(r.out + x, ok ? narrow((Sww * ggq_c - Swg * wgq_c) / det) : VF{});
}
void detail_row_sse(const DetailRow& r) {
  for (int x = r.lo; x < r.hi; ++x) detail_one(r, x);
}
__attribute__((target("avx2"))) void detail_row_avx2(const DetailRow& row) {
  const DetailRow r = row;  // as in fit_row_avx2
  int x = r.lo;
  for (; x + 4 <= r.hi; x += 4) detail4(r, x);
  for (; x < r.hi; ++x) detail_one(r, x);
}

inline void update_one(const UpdateRow& r, int x) {
  if (!(r.solved[x] > 0)) {
    r.d[x] = kNan;
    return;
  }
  const float move = r.q_win[x] - r.q[x];
  const float noise = 3.f * std::sqrt(r.s2[x] * r.z[x]);
  const bool smooth = std::abs(r.q[x]) <= noise && std::abs(move) <= noise;
  r.d[x] += r.step[x] + (smooth ? move : 0.f);
}
void update_row_sse(const UpdateRow& r) {
  for (int x = r.lo; x < r.hi; ++x) update_one(r, x);
}
// sqrt and the absolute values by instructions (both exact: the scalar code's bits).
__attribute__((target("avx2"))) void update_row_avx2(const UpdateRow& row) {
  const UpdateRow r = row;  // as in fit_row_avx2
  const __m256 sign = _mm256_set1_ps(-0.f), zero = _mm256_setzero_ps();
  int x = r.lo;
  for (; x + 8 <= r.hi; x += 8) {
    const __m256 q = _mm256_loadu_ps(r.q + x), move = _mm256_sub_ps(_mm256_loadu_ps(r.q_win + x), q);
    const __m256 noise =
        _mm256_mul_ps(_mm256_set1_ps(3.f),
                      _mm256_sqrt_ps(_mm256_mul_ps(_mm256_loadu_ps(r.s2 + x), _mm256_loadu_ps(r.z + x))));
    const __m256 smooth = _mm256_and_ps(_mm256_cmp_ps(_mm256_andnot_ps(sign, q), noise, _CMP_LE_OQ),
                                        _mm256_cmp_ps(_mm256_andnot_ps(sign, move), noise, _CMP_LE_OQ));
    const __m256 d = _mm256_add_ps(_mm256_loadu_ps(r.d + x),
                                   _mm256_add_ps(_mm256_loadu_ps(r.step + x), _mm256_and_ps(smooth, move)));
    const __m256 solved = _mm256_cmp_ps(_mm256_loadu_ps(r.solved + x), zero, _CMP_GT_OQ);
    _mm256_storeu_ps(r.d + x, _mm256_blendv_ps(_mm256_set1_ps(kNan), d, solved));
  }
  for (; x < r.hi; ++x) update_one(r, x);
}

template <class V>
inline __attribute__((always_inline)) void mean_v(const float* sum, const float* cnt, float* d, float* moved,
                                                  int x) {
  const V zero = V{}, dv = ld<V>(d + x), c = ld<V>(cnt + x);
  const V next = c > zero ? ld<V>(sum + x) / c : dv;
  const auto finite = dv - dv == zero;
  st(moved + x, finite ? next - dv : ld<V>(moved + x));
  st(d + x, finite ? next : dv);
}
inline void mean_one(const float* sum, const float* cnt, float* d, float* moved, int x) {
  if (!std::isfinite(d[x])) return;
  const float next = cnt[x] > 0 ? sum[x] / cnt[x] : d[x];
  moved[x] = next - d[x];
  d[x] = next;
}
void mean_row_sse(const float* sum, const float* cnt, float* d, float* moved, int lo, int hi) {
  int x = lo;
  for (; x + 4 <= hi; x += 4) mean_v<VF>(sum, cnt, d, moved, x);
  for (; x < hi; ++x) mean_one(sum, cnt, d, moved, x);
}
__attribute__((target("avx2"))) void mean_row_avx2(const float* sum, const float* cnt, float* d, float* moved,
                                                   int lo, int hi) {
  int x = lo;
  for (; x + 8 <= hi; x += 8) mean_v<V8>(sum, cnt, d, moved, x);
  for (; x < hi; ++x) mean_one(sum, cnt, d, moved, x);
}

// correlation()'s steps per pixel or lane: T is float (the tails) or a vector, the same expressions.
template <class T>
inline __attribute__((always_inline)) void residual_at(const ResidualRow& r, float thr, std::size_t i) {
  const T d = ld<T>(r.d + i), e = ld<T>(r.a + i) * ld<T>(r.w + i) + ld<T>(r.b + i) -
                                  ld<T>(r.c + i) * ld<T>(r.g + i) - ld<T>(r.l + i);
  st(r.e + i, (ld<T>(r.m + i) > 0.f) & (d - d == 0.f) & (ld<T>(r.s2 + i) <= thr) ? e : T{});
}
template <class T>
inline __attribute__((always_inline)) void centre_at(const float* m, const float* g, const float* sg,
                                                     const float* sn, float* z, float* zz, float* zh, int x) {
  const T one = T{} + 1.f, n = ld<T>(sn + x);
  const T zv = ld<T>(m + x) > 0.f ? ld<T>(g + x) - ld<T>(sg + x) / (1.f < n ? n : one) : T{};
  st(z + x, zv);
  st(zz + x, zv * zv);
  st(zh + x, T{});
}
template <class T>
inline __attribute__((always_inline)) void kappa_at(const float* szz, const float* szh, float* kappa, int x) {
  const T s = ld<T>(szz + x), q = ld<T>(szh + x) / s;
  st(kappa + x, s > 0.f ? (0.f < q ? q : T{}) : T{} + 1.f);
}

// The largest float <= lim: s2 <= it exactly where the float s2 <= lim in double.
float floor_to_float(double lim) {
  float t = static_cast<float>(lim);
  if (static_cast<double>(t) > lim) t = std::nextafter(t, -std::numeric_limits<float>::infinity());
  return t;
}

template <class V>
inline __attribute__((always_inline)) void residual_v(const ResidualRow& r, double lim, std::size_t lo,
                                                      std::size_t hi) {
  const float thr = floor_to_float(lim);
  std::size_t i = lo;
  for (; i + sizeof(V) / 4 <= hi; i += sizeof(V) / 4) residual_at<V>(r, thr, i);
  for (; i < hi; ++i) residual_at<float>(r, thr, i);
}
template <class V>
inline __attribute__((always_inline)) void centre_v(const float* m, const float* g, const float* sg,
                                                    const float* sn, float* z, float* zz, float* zh, int lo,
                                                    int hi) {
  int x = lo;
  for (; x + static_cast<int>(sizeof(V) / 4) <= hi; x += sizeof(V) / 4)
    centre_at<V>(m, g, sg, sn, z, zz, zh, x);
  for (; x < hi; ++x) centre_at<float>(m, g, sg, sn, z, zz, zh, x);
}
template <class V>
inline __attribute__((always_inline)) void kappa_v(const float* szz, const float* szh, float* kappa, int lo,
                                                   int hi) {
  int x = lo;
  for (; x + static_cast<int>(sizeof(V) / 4) <= hi; x += sizeof(V) / 4) kappa_at<V>(szz, szh, kappa, x);
  for (; x < hi; ++x) kappa_at<float>(szz, szh, kappa, x);
}

void residual_sse(const ResidualRow& r, double lim, std::size_t lo, std::size_t hi) {
  residual_v<VF>(r, lim, lo, hi);
}
__attribute__((target("avx2"))) void residual_avx2(const ResidualRow& r, double lim, std::size_t lo,
                                                   std::size_t hi) {
  residual_v<V8>(r, lim, lo, hi);
}
void centre_sse(const float* m, const float* g, const float* sg, const float* sn, float* z, float* zz,
                float* zh, int lo, int hi) {
  centre_v<VF>(m, g, sg, sn, z, zz, zh, lo, hi);
}
__attribute__((target("avx2"))) void centre_avx2(const float* m, const float* g, const float* sg,
                                                 const float* sn, float* z, float* zz, float* zh, int lo,
                                                 int hi) {
  centre_v<V8>(m, g, sg, sn, z, zz, zh, lo, hi);
}
void kappa_sse(const float* szz, const float* szh, float* kappa, int lo, int hi) {
  kappa_v<VF>(szz, szh, kappa, lo, hi);
}
__attribute__((target("avx2"))) void kappa_avx2(const float* szz, const float* szh, float* kappa, int lo,
                                                int hi) {
  kappa_v<V8>(szz, szh, kappa, lo, hi);
}

}  // namespace

void residual_row(bool avx2, const ResidualRow& r, double lim, std::size_t lo, std::size_t hi) {
  (avx2 ? residual_avx2 : residual_sse)(r, lim, lo, hi);
}

void centre_row(bool avx2, const float* m, const float* g, const float* sg, const float* sn, float* z,
                float* zz, float* zh, int lo, int hi) {
  (avx2 ? centre_avx2 : centre_sse)(m, g, sg, sn, z, zz, zh, lo, hi);
}

void kappa_row(bool avx2, const float* szz, const float* szh, float* kappa, int lo, int hi) {
  (avx2 ? kappa_avx2 : kappa_sse)(szz, szh, kappa, lo, hi);
}

void fit_row(bool avx2, const FitRow& r) {
  (avx2 ? fit_row_avx2 : fit_row_sse)(r);
}

void detail_row(bool avx2, const DetailRow& r) {
  (avx2 ? detail_row_avx2 : detail_row_sse)(r);
}

void update_row(bool avx2, const UpdateRow& r) {
  (avx2 ? update_row_avx2 : update_row_sse)(r);
}

void mean_row(bool avx2, const float* sum, const float* cnt, float* d, float* moved, int lo, int hi) {
  (avx2 ? mean_row_avx2 : mean_row_sse)(sum, cnt, d, moved, lo, hi);
}

}  // namespace naneye::recon::scene::dense_simd

#undef NANEYE_AVX2_INLINE

#pragma GCC diagnostic pop
