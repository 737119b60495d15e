// See dense_simd.hpp. The vector helpers are corners/simd.hpp's (inlined only into the entry points
// below, each compiled for its own target).
#include "dense_simd.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include <immintrin.h>

#include "../corners/simd.hpp"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

namespace naneye::recon::scene::dense_simd {
namespace {
using simd::kLanes;
using simd::load;
using simd::store;

// Per output row, 2r+1 input rows added into one row (`tmp`, w floats, stays in the first-level
// cache), then 2r+1 of its columns, in float. Direct sums rather than running ones: nothing drifts
// along a row, and every inner loop is an array add over whole vectors. Each output's additions
// come in the same order as in a plain scalar loop (rows top to bottom, then columns left to right).
// R > 0: the radius known at compile time (the matcher's 3 .. 5 and twice them), so both tap loops unroll
// into one load-add per tap; with the radius a run-time count the loop control cost as much as the
// adds (callgrind: ~12 instructions per pixel, 49 M per pair). R = 0: any radius r.
template <class V, int R>
NANEYE_SIMD_INLINE void box_sum_v(const float* __restrict in, float* __restrict out, float* __restrict tmp,
                                  const Spans& sp, int r_any) {
  constexpr int L = kLanes<V>;
  const int r = R > 0 ? R : r_any;
  const int w = sp.w, h = sp.h;
  const int inner0 = std::min(r, w), inner1 = std::max(inner0, w - r);
  for (int y = 0; y < h; ++y) {
    const int lo = sp.lo[y], hi = sp.hi[y];
    if (lo >= hi) continue;
    const int c0 = std::max(0, lo - r), c1 = std::min(w, hi + r);
    const int y0 = std::max(0, y - r), y1 = std::min(h - 1, y + r);
    const float* first = in + static_cast<std::size_t>(y0) * w;
    int x = c0;
    if (R > 0 && y1 - y0 == 2 * R) {
      for (; x + L <= c1; x += L) {
        V acc = load<V>(first + x);
#pragma GCC unroll 24
        for (int k = 1; k <= 2 * R; ++k) acc += load<V>(first + static_cast<std::size_t>(k) * w + x);
        store(tmp + x, acc);
      }
    } else {
      for (; x + L <= c1; x += L) {
        V acc = load<V>(first + x);
        for (int yy = y0 + 1; yy <= y1; ++yy) acc += load<V>(in + static_cast<std::size_t>(yy) * w + x);
        store(tmp + x, acc);
      }
    }
    // The last columns as one more vector (the scalar tail was ~2 M instructions a pair), ending at
    // most at the row's end: it sums again columns already summed (the same sums) or sums columns
    // beyond c1, which nothing reads.
    if (const int xv = std::min(x, w - L); x < c1 && xv >= 0) {
      V acc = load<V>(first + xv);
      for (int yy = y0 + 1; yy <= y1; ++yy) acc += load<V>(in + static_cast<std::size_t>(yy) * w + xv);
      store(tmp + xv, acc);
      x = c1;
    }
    for (; x < c1; ++x) {
      float acc = first[x];
      for (int yy = y0 + 1; yy <= y1; ++yy) acc += in[static_cast<std::size_t>(yy) * w + x];
      tmp[x] = acc;
    }
    float* o = out + static_cast<std::size_t>(y) * w;
    auto edge = [&](int xe) {
      float s = 0;
      for (int k = std::max(0, xe - r); k <= std::min(w - 1, xe + r); ++k) s += tmp[k];
      o[xe] = s;
    };
    const int i0 = std::max(lo, inner0), i1 = std::min(hi, inner1);
    for (x = lo; x < std::min(hi, inner0); ++x) edge(x);
    // Inner columns: tmp[x - r .. x + r] all inside [c0, c1).
    for (x = i0; x + L <= i1; x += L) {
      V acc = load<V>(tmp + x - r);
#pragma GCC unroll 24
      for (int k = 1 - r; k <= r; ++k) acc += load<V>(tmp + x + k);
      store(o + x, acc);
    }
    if (x < i1 && x + L + r <= w) {  // the tail's lanes, the ones beyond i1 dropped
      V acc = load<V>(tmp + x - r);
      for (int k = 1 - r; k <= r; ++k) acc += load<V>(tmp + x + k);
      alignas(32) float lanes[L];
      store(lanes, acc);
      std::copy(lanes, lanes + (i1 - x), o + x);
      x = i1;
    }
    for (; x < i1; ++x) {
      float acc = tmp[x - r];
      for (int k = 1 - r; k <= r; ++k) acc += tmp[x + k];
      o[x] = acc;
    }
    for (x = std::max(lo, inner1); x < hi; ++x) edge(x);
  }
}

template <class V>
NANEYE_SIMD_INLINE void box_sum_any(const float* in, float* out, float* tmp, const Spans& sp, int r) {
  // The radii the matcher chooses from (MatcherSettings::radius .. max_radius, 3 .. 6 by default)
  // and twice them (reference_detail); any other through the general loop (the same sums' bits).
  switch (r) {
    case 3:
      return box_sum_v<V, 3>(in, out, tmp, sp, r);
    case 4:
      return box_sum_v<V, 4>(in, out, tmp, sp, r);
    case 5:
      return box_sum_v<V, 5>(in, out, tmp, sp, r);
    case 6:
      return box_sum_v<V, 6>(in, out, tmp, sp, r);
    case 8:
      return box_sum_v<V, 8>(in, out, tmp, sp, r);
    case 10:
      return box_sum_v<V, 10>(in, out, tmp, sp, r);
    case 12:
      return box_sum_v<V, 12>(in, out, tmp, sp, r);
    default:
      return box_sum_v<V, 0>(in, out, tmp, sp, r);
  }
}

// One lag at a time over whole rows: out + rho_lag z, in the lags' row-major order for every pixel.
template <class V>
NANEYE_SIMD_INLINE void filter_lags_v(const float* __restrict z, float* __restrict out, const float* rho,
                                      int lag, const Spans& sp) {
  constexpr int L = kLanes<V>;
  const int side = 2 * lag + 1, w = sp.w, h = sp.h;
  for (int dy = -lag; dy <= lag; ++dy)
    for (int dx = -lag; dx <= lag; ++dx) {
      const float r = rho[(dy + lag) * side + dx + lag];
      for (int y = std::max(0, -dy); y < std::min(h, h - dy); ++y) {
        const int x0 = std::max(sp.lo[y], -dx), x1 = std::min(sp.hi[y], w - dx);
        float* __restrict o = out + static_cast<std::size_t>(y) * w;
        const float* __restrict src = z + static_cast<std::size_t>(y + dy) * w + dx;
        int x = x0;
        for (; x + L <= x1; x += L) store(o + x, load<V>(o + x) + r * load<V>(src + x));
        for (; x < x1; ++x) o[x] += r * src[x];
      }
    }
}

// The 7 lags of a row as one block of 8 floats (the eighth a lane no output keeps): per lag row one
// or two float multiplies and their conversions and double adds on whole vectors, each sum's
// additions in the plain loop's order. The plain loop kept 49 double sums in memory, a load, a
// convert, an add and a store per product (~0.5 ms per pair in perf).
using VD2 = double __attribute__((vector_size(16)));
using VD4 = double __attribute__((vector_size(32)));

template <class V>
NANEYE_SIMD_INLINE void lag_products_v(const float* e, int w, int h, double* acc) {
  constexpr int L = kLanes<V>, H = L / 2, kLag = 3, kSide = 2 * kLag + 1;
  using VD = std::conditional_t<L == 8, VD4, VD2>;  // half the floats' lanes, as doubles
  VD a[kSide][8 / H] = {};
  const std::size_t n = static_cast<std::size_t>(w) * h;
  for (int y = kLag; y < h - kLag; y += 2)
    for (int x = kLag; x < w - kLag; x += 2) {
      const float ei = e[static_cast<std::size_t>(y) * w + x];
      if (ei == 0) continue;
      for (int dy = 0; dy < kSide; ++dy) {
        const std::size_t at = static_cast<std::size_t>(y + dy - kLag) * w + x - kLag;
        const float* src = e + at;
        alignas(32) float pad[8] = {};
        if (at + 8 > n) {  // the last row's last pixel: the eighth lane would leave the plane
          std::copy(src, e + n, pad);
          src = pad;
        }
        for (int b = 0; b < 8 / L; ++b) {
          const V p = ei * load<V>(src + b * L);
          if constexpr (L == 8) {
            a[dy][2 * b] += __builtin_convertvector(__builtin_shufflevector(p, p, 0, 1, 2, 3), VD);
            a[dy][2 * b + 1] += __builtin_convertvector(__builtin_shufflevector(p, p, 4, 5, 6, 7), VD);
          } else {
            a[dy][2 * b] += __builtin_convertvector(__builtin_shufflevector(p, p, 0, 1), VD);
            a[dy][2 * b + 1] += __builtin_convertvector(__builtin_shufflevector(p, p, 2, 3), VD);
          }
        }
      }
    }
  for (int dy = 0; dy < kSide; ++dy)
    for (int dx = 0; dx < kSide; ++dx) acc[dy * kSide + dx] = a[dy][dx / H][dx % H];
}

// A block's taps and left pixels, less mu, its offsets t from tap 0 and its mask (all zero where
// the pixel has no four valid taps or lies beyond `count`): per lane, in scalar code.
struct Taps {
  alignas(32) float T[8], R[4][8], Lv[8], Gl[8], M[8];
};
template <int L>
NANEYE_SIMD_INLINE void pick_lanes(const GatherRow& g, int x, int count, Taps& p) {
  for (int j = 0; j < L; ++j) {
    p.T[j] = p.R[0][j] = p.R[1][j] = p.R[2][j] = p.R[3][j] = p.Lv[j] = p.Gl[j] = p.M[j] = 0.f;
    if (j >= count) continue;
    const float d = g.d[x + j];
    if (!std::isfinite(d)) continue;
    const float xs = static_cast<float>(x + j) - d;
    const int i0 = static_cast<int>(std::floor(xs));
    if (i0 < 1 || i0 + 2 >= g.w || !g.taps_ok[i0] || !std::isfinite(g.left_grad[x + j])) continue;
    p.T[j] = xs - static_cast<float>(i0);
    for (int k = 0; k < 4; ++k) p.R[k][j] = g.right[i0 - 1 + k] - g.mu;
    p.Lv[j] = g.left[x + j] - g.mu;
    p.Gl[j] = g.left_grad[x + j];
    p.M[j] = 1.f;
  }
}

// The same for 8 whole lanes in AVX2, the same float operations per lane: the position, floor and
// range tests on vectors, each lane's four taps one 16-byte load (they are contiguous), transposed
// into the four tap vectors. Lanes without taps load from column 1 (always inside the row, w >= 4)
// and are masked to zero. No gathers for the taps: on this AMD EPYC five per block gave half the
// instructions but no time (docs/scene.md, 2026-12-04 night); loads and shuffles are cheap.
__attribute__((target("avx2"))) NANEYE_SIMD_INLINE void pick_avx2(const GatherRow& g, int x, Taps& p) {
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256 d = _mm256_loadu_ps(g.d + x);
  const __m256 xs = _mm256_sub_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32(x), lane)), d);
  // cvttps gives INT_MIN beyond int's range, as the scalar conversion does on x86: refused by i0 >= 1.
  const __m256i i0 = _mm256_cvttps_epi32(_mm256_floor_ps(xs));
  const __m256 finite = _mm256_cmp_ps(_mm256_sub_ps(d, d), _mm256_setzero_ps(), _CMP_EQ_OQ);
  const __m256i in_row = _mm256_and_si256(_mm256_cmpgt_epi32(i0, _mm256_setzero_si256()),
                                          _mm256_cmpgt_epi32(_mm256_set1_epi32(g.w - 2), i0));
  const __m256i ok = _mm256_and_si256(_mm256_castps_si256(finite), in_row);
  alignas(32) int idx[8];
  const __m256i at = _mm256_blendv_epi8(_mm256_set1_epi32(1), i0, ok);
  _mm256_store_si256(reinterpret_cast<__m256i*>(idx), at);
  // taps_ok[i0] of the lanes in the row by one masked gather of 32 bits at byte i0 - 1 (bytes i0 - 1
  // .. i0 + 2, all inside the row; the other lanes read nothing): its second byte. One instruction
  // where eight scalar loads and bit inserts took ~35 (~3 M instructions a pair).
  const __m256i word =
      _mm256_mask_i32gather_epi32(_mm256_setzero_si256(), reinterpret_cast<const int*>(g.taps_ok),
                                  _mm256_sub_epi32(at, _mm256_set1_epi32(1)), ok, 1);
  const __m256 grad = _mm256_loadu_ps(g.left_grad + x);
  const __m256 has_grad = _mm256_cmp_ps(_mm256_sub_ps(grad, grad), _mm256_setzero_ps(), _CMP_EQ_OQ);
  const __m256 mask = _mm256_and_ps(
      has_grad,
      _mm256_castsi256_ps(_mm256_andnot_si256(
          _mm256_cmpeq_epi32(_mm256_and_si256(word, _mm256_set1_epi32(0xff00)), _mm256_setzero_si256()),
          ok)));
  const float* r = g.right - 1;
  __m256 a[4];
  for (int k = 0; k < 4; ++k)
    a[k] = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(r + idx[k])),
                                _mm_loadu_ps(r + idx[k + 4]), 1);
  const __m256 t0 = _mm256_unpacklo_ps(a[0], a[1]), t1 = _mm256_unpackhi_ps(a[0], a[1]);
  const __m256 t2 = _mm256_unpacklo_ps(a[2], a[3]), t3 = _mm256_unpackhi_ps(a[2], a[3]);
  const __m256 tap[4] = {_mm256_shuffle_ps(t0, t2, 0x44), _mm256_shuffle_ps(t0, t2, 0xee),
                         _mm256_shuffle_ps(t1, t3, 0x44), _mm256_shuffle_ps(t1, t3, 0xee)};
  const __m256 mu = _mm256_set1_ps(g.mu);
  _mm256_store_ps(p.T, _mm256_and_ps(mask, _mm256_sub_ps(xs, _mm256_cvtepi32_ps(i0))));
  for (int k = 0; k < 4; ++k) _mm256_store_ps(p.R[k], _mm256_and_ps(mask, _mm256_sub_ps(tap[k], mu)));
  _mm256_store_ps(p.Lv, _mm256_and_ps(mask, _mm256_sub_ps(_mm256_loadu_ps(g.left + x), mu)));
  _mm256_store_ps(p.Gl, _mm256_and_ps(mask, grad));
  _mm256_store_ps(p.M, _mm256_and_ps(mask, _mm256_set1_ps(1.f)));
}

// The cubic B-spline's weights and the ten products of a block of L picked pixels on whole vectors, with the
// scalar code's expressions term by term; stored to the row's channels at x (count lanes).
template <class V>
NANEYE_SIMD_INLINE void gather_block(const GatherRow& g, const Taps& p, int x, int count) {
  constexpr int L = kLanes<V>;
  // The cubic B-spline (the row holds its coefficients: bspline.hpp) at offset t in [0, 1) from
  // tap 0, for taps -1, 0, 1, 2.
  const V t = load<V>(p.T), t2 = t * t, t3 = t2 * t;
  const V s = 1.f - t;
  const V w0 = (1.f / 6.f) * (s * s * s), w1 = 0.5f * t3 - t2 + 2.f / 3.f;
  const V w2 = -0.5f * t3 + 0.5f * t2 + 0.5f * t + 1.f / 6.f, w3 = (1.f / 6.f) * t3;
  const V r0 = load<V>(p.R[0]), r1 = load<V>(p.R[1]), r2 = load<V>(p.R[2]), r3 = load<V>(p.R[3]);
  V W = V{};
  W += w0 * r0;
  W += w1 * r1;
  W += w2 * r2;
  W += w3 * r3;
  const V m = load<V>(p.M), l = load<V>(p.Lv), G = load<V>(p.Gl);
  const V out[10] = {m,         m * W,     m * l,     m * G,     m * W * W,
                     m * G * G, m * W * G, m * W * l, m * G * l, m * l * l};
  for (int c = 0; c < 10; ++c)
    if (count == L) {
      store(g.ch[c] + x, out[c]);
    } else {
      alignas(32) float o[L];
      store(o, out[c]);
      for (int j = 0; j < count; ++j) g.ch[c][x + j] = o[j];
    }
}

void box_sum_sse(const float* in, float* out, float* tmp, const Spans& sp, int r) {
  box_sum_any<simd::V4>(in, out, tmp, sp, r);
}
__attribute__((target("avx2"))) void box_sum_avx2(const float* in, float* out, float* tmp, const Spans& sp,
                                                  int r) {
  box_sum_any<simd::V8>(in, out, tmp, sp, r);
}
void filter_lags_sse(const float* z, float* out, const float* rho, int lag, const Spans& sp) {
  filter_lags_v<simd::V4>(z, out, rho, lag, sp);
}
__attribute__((target("avx2"))) void filter_lags_avx2(const float* z, float* out, const float* rho, int lag,
                                                      const Spans& sp) {
  filter_lags_v<simd::V8>(z, out, rho, lag, sp);
}
// The row structs are copied in: every store (memcpy, or an intrinsic's may-alias type) could write
// the caller's pointers, which would then be reloaded after each one.
void gather_row_sse(const GatherRow& row) {
  const GatherRow g = row;
  Taps p;
  for (int x = g.lo; x < g.hi; x += 4) {
    const int count = std::min(4, g.hi - x);
    pick_lanes<4>(g, x, count, p);
    gather_block<simd::V4>(g, p, x, count);
  }
}
// pick_avx2 is called here, not from a template: GCC inlines an AVX2 function only into another.
__attribute__((target("avx2"))) void gather_row_avx2(const GatherRow& row) {
  const GatherRow g = row;
  Taps p;
  for (int x = g.lo; x < g.hi; x += 8) {
    const int count = std::min(8, g.hi - x);
    if (count == 8 && g.w >= 4)
      pick_avx2(g, x, p);
    else
      pick_lanes<8>(g, x, count, p);
    gather_block<simd::V8>(g, p, x, count);
  }
}
void lag_products_sse(const float* e, int w, int h, double* acc) {
  lag_products_v<simd::V4>(e, w, h, acc);
}
__attribute__((target("avx2"))) void lag_products_avx2(const float* e, int w, int h, double* acc) {
  lag_products_v<simd::V8>(e, w, h, acc);
}
}  // namespace

void box_sum(bool avx2, const float* in, float* out, float* tmp, const Spans& sp, int r) {
  (avx2 ? box_sum_avx2 : box_sum_sse)(in, out, tmp, sp, r);
}

void filter_lags(bool avx2, const float* z, float* out, const float* rho, int lag, const Spans& sp) {
  (avx2 ? filter_lags_avx2 : filter_lags_sse)(z, out, rho, lag, sp);
}

void gather_row(bool avx2, const GatherRow& g) {
  (avx2 ? gather_row_avx2 : gather_row_sse)(g);
}

void lag_products(bool avx2, const float* e, int w, int h, double acc[49]) {
  (avx2 ? lag_products_avx2 : lag_products_sse)(e, w, h, acc);
}

}  // namespace naneye::recon::scene::dense_simd

#pragma GCC diagnostic pop
