// See sgm_simd.hpp: the vector builds and the run-time choice. The scalar reference they are tested
// against is in sgm_scalar.cpp; the vector templates are inlined only into their entry points, each
// compiled for its own target.
#include "sgm_simd.hpp"

#include "sgm_scalar.hpp"

#include <algorithm>
#include <cstring>

// The 32-byte helpers run only inlined into AVX2 functions, never across a call boundary whose ABI
// would depend on the target; GCC reports them at the end of the unit, so the note stays off to
// its end (as in corners/simd.cpp).
#pragma GCC diagnostic ignored "-Wpsabi"

namespace naneye::recon::scene::sgm_simd {
namespace {

#define NANEYE_SGM_INLINE inline __attribute__((always_inline))

// One vector width's types: floats and 32-bit lanes (census, Hamming), and 16-bit lanes (costs).
// (GCC takes vector_size only with a constant, not a template parameter: one specialisation each.)
template <int Bytes>
struct Vec;
template <>
struct Vec<16> {
  using F = float __attribute__((vector_size(16)));
  using U = std::uint32_t __attribute__((vector_size(16)));
  using H = std::int16_t __attribute__((vector_size(16)));
  using HalfH = std::int16_t __attribute__((vector_size(8)));  // U's lanes narrowed
  static constexpr int k32 = 4, k16 = 8;
};
template <>
struct Vec<32> {
  using F = float __attribute__((vector_size(32)));
  using U = std::uint32_t __attribute__((vector_size(32)));
  using H = std::int16_t __attribute__((vector_size(32)));
  using HalfH = std::int16_t __attribute__((vector_size(16)));
  static constexpr int k32 = 8, k16 = 16;
};

template <class T, class P>
NANEYE_SGM_INLINE T load(const P* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
template <class T, class P>
NANEYE_SGM_INLINE void store(P* p, T v) {
  std::memcpy(p, &v, sizeof v);
}
template <class T>
NANEYE_SGM_INLINE T vmin(T a, T b) {
  return a < b ? a : b;
}

using scalar::above;
using scalar::kCensusR;
using scalar::Pred;

// ---- vector builds -------------------------------------------------------------------------

template <int B>
NANEYE_SGM_INLINE void census_v(const float* img, std::size_t stride, int w, int h, int y, int x0, int x1,
                                std::uint32_t* out) {
  using F = typename Vec<B>::F;
  using U = typename Vec<B>::U;
  constexpr int L = Vec<B>::k32;
  if (y < kCensusR || y >= h - kCensusR) {
    for (int x = x0; x < x1; ++x) out[x] = 0;
    return;
  }
  const int in0 = std::clamp(x0, kCensusR, std::max(kCensusR, w - kCensusR));
  const int in1 = std::clamp(x1, in0, std::max(in0, w - kCensusR));
  scalar::census(img, stride, w, h, y, x0, in0, out);  // border columns: scalar (zero)
  const float* row = img + static_cast<std::size_t>(y) * stride;
  int x = in0;
  for (; x + L <= in1; x += L) {
    const F c = load<F>(row + x);
    U bits = U{} + 0u, bit = U{} + 1u;
    for (int dy = -kCensusR; dy <= kCensusR; ++dy)
      for (int dx = -kCensusR; dx <= kCensusR; ++dx) {
        if (dy == 0 && dx == 0) continue;
        const F n = load<F>(row + dy * static_cast<std::ptrdiff_t>(stride) + x + dx);
        bits |= reinterpret_cast<U>(n > c) & bit;  // comparisons give all ones (true) per lane
        bit <<= 1;
      }
    store(out + x, bits);
  }
  scalar::census(img, stride, w, h, y, x, x1, out);  // the tail and the right border
}

template <int B>
NANEYE_SGM_INLINE void hamming_v(const std::uint32_t* cl, const std::uint32_t* cr_rev, int w, int dmin, int D,
                                 int x0, int x1, std::int16_t* H) {
  using U = typename Vec<B>::U;
  using HalfH = typename Vec<B>::HalfH;
  constexpr int L = Vec<B>::k32;
  for (int x = x0; x < x1; ++x) {
    const U l = U{} + cl[x];
    const std::uint32_t* r = cr_rev + (w - 1 - x + dmin);
    std::int16_t* o = H + static_cast<std::size_t>(x) * D;
    for (int d = 0; d < D; d += L) {  // D is a multiple of 16 (Sgm's constructor)
      // Population count by halving sums (no multiply: SSE2 has no 32-bit lane product).
      U v = l ^ load<U>(r + d);
      v = v - ((v >> 1) & 0x55555555u);
      v = (v & 0x33333333u) + ((v >> 2) & 0x33333333u);
      v = (v + (v >> 4)) & 0x0f0f0f0fu;
      v = v + (v >> 8);
      v = (v + (v >> 16)) & 0x3fu;
      store(o + d, __builtin_convertvector(v, HalfH));
    }
  }
}

template <int B>
NANEYE_SGM_INLINE void hsum3_v(const std::int16_t* H, int D, int h0, int h1, int x0, int x1,
                               std::int16_t* out) {
  using V = typename Vec<B>::H;
  constexpr int L = Vec<B>::k16;
  for (int x = x0; x < x1; ++x) {
    const std::int16_t* a = H + static_cast<std::size_t>(std::max(h0, x - 1)) * D;
    const std::int16_t* b = H + static_cast<std::size_t>(x) * D;
    const std::int16_t* c = H + static_cast<std::size_t>(std::min(h1 - 1, x + 1)) * D;
    std::int16_t* o = out + static_cast<std::size_t>(x) * D;
    for (int d = 0; d < D; d += L) store(o + d, load<V>(a + d) + load<V>(b + d) + load<V>(c + d));
  }
}

template <int B>
NANEYE_SGM_INLINE void add3_v(const std::int16_t* a, const std::int16_t* b, const std::int16_t* c, int D,
                              int x0, int x1, std::int16_t* out) {
  using V = typename Vec<B>::H;
  constexpr int L = Vec<B>::k16;
  for (std::size_t i = static_cast<std::size_t>(x0) * D; i < static_cast<std::size_t>(x1) * D; i += L)
    store(out + i, load<V>(a + i) + load<V>(b + i) + load<V>(c + i));
}

// The smallest lane, by halving: each step takes the lane-wise minimum with the other half.
template <int B>
NANEYE_SGM_INLINE int hmin(typename Vec<B>::H v) {
  using V = typename Vec<B>::H;
  if constexpr (B == 32)
    v = vmin(v, __builtin_shuffle(v, V{8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3, 4, 5, 6, 7}));
  if constexpr (B == 32) {
    v = vmin(v, __builtin_shuffle(v, V{4, 5, 6, 7, 0, 1, 2, 3, 12, 13, 14, 15, 8, 9, 10, 11}));
    v = vmin(v, __builtin_shuffle(v, V{2, 3, 0, 1, 6, 7, 4, 5, 10, 11, 8, 9, 14, 15, 12, 13}));
    v = vmin(v, __builtin_shuffle(v, V{1, 0, 3, 2, 5, 4, 7, 6, 9, 8, 11, 10, 13, 12, 15, 14}));
  } else {
    v = vmin(v, __builtin_shuffle(v, V{4, 5, 6, 7, 0, 1, 2, 3}));
    v = vmin(v, __builtin_shuffle(v, V{2, 3, 0, 1, 6, 7, 4, 5}));
    v = vmin(v, __builtin_shuffle(v, V{1, 0, 3, 2, 5, 4, 7, 6}));
  }
  return v[0];
}

// Eq. 13 (sgm_scalar.cpp's path) on L disparities from d; jump = min_k L_r(p - r, k) + P2 is formed here
// rather than kept per path (four fewer live registers in the forward loop).
template <int B>
NANEYE_SGM_INLINE typename Vec<B>::H path_v(const std::int16_t* prev, int d, typename Vec<B>::H prev_min,
                                            typename Vec<B>::H p1, typename Vec<B>::H p2,
                                            typename Vec<B>::H c) {
  using V = typename Vec<B>::H;
  const V a = load<V>(prev + 1 + d), lo = load<V>(prev + d) + p1, hi = load<V>(prev + 2 + d) + p1;
  return vmin(vmin(a, lo), vmin(hi, prev_min + p2)) + c - prev_min;
}

// The four forward paths written out (no arrays of vectors: GCC kept those in memory).
template <int B>
NANEYE_SGM_INLINE void aggregate_v(const PathRow& r) {
  using V = typename Vec<B>::H;
  constexpr int L = Vec<B>::k16;
  const int D = r.D;
  const std::size_t Ds = static_cast<std::size_t>(D) + 2;
  const V p1 = V{} + r.p1, p2 = V{} + r.p2;
  int h_min = 0;
  for (int x = r.lo; x < r.hi; ++x) {
    const std::int16_t* c = r.cost + static_cast<std::size_t>(x) * D;
    std::int16_t* s = r.sum + static_cast<std::size_t>(x) * D;
    const Pred q0 = x > r.lo ? Pred{r.horiz[(x - 1) & 1], h_min} : Pred{r.start, 0};
    const Pred q1 = above(r, 0, x - 1), q2 = above(r, 1, x), q3 = above(r, 2, x + 1);
    std::int16_t* o0 = r.horiz[x & 1];
    std::int16_t* o1 = r.cur[0] + static_cast<std::size_t>(x) * Ds;
    std::int16_t* o2 = r.cur[1] + static_cast<std::size_t>(x) * Ds;
    std::int16_t* o3 = r.cur[2] + static_cast<std::size_t>(x) * Ds;
    const V pm0 = V{} + static_cast<std::int16_t>(q0.min), pm1 = V{} + static_cast<std::int16_t>(q1.min);
    const V pm2 = V{} + static_cast<std::int16_t>(q2.min), pm3 = V{} + static_cast<std::int16_t>(q3.min);
    V m0 = V{} + kPad, m1 = m0, m2 = m0, m3 = m0;
    for (int d = 0; d < D; d += L) {
      const V cv = load<V>(c + d);
      const V v0 = path_v<B>(q0.block, d, pm0, p1, p2, cv);
      const V v1 = path_v<B>(q1.block, d, pm1, p1, p2, cv);
      const V v2 = path_v<B>(q2.block, d, pm2, p1, p2, cv);
      const V v3 = path_v<B>(q3.block, d, pm3, p1, p2, cv);
      store(o0 + 1 + d, v0);
      store(o1 + 1 + d, v1);
      store(o2 + 1 + d, v2);
      store(o3 + 1 + d, v3);
      m0 = vmin(m0, v0);
      m1 = vmin(m1, v1);
      m2 = vmin(m2, v2);
      m3 = vmin(m3, v3);
      store(s + d, (v0 + v1) + (v2 + v3));  // exact in int16 (S < kPad): any order gives the same bits
    }
    h_min = hmin<B>(m0);
    r.cur_min[0][x] = static_cast<std::int16_t>(hmin<B>(m1));
    r.cur_min[1][x] = static_cast<std::int16_t>(hmin<B>(m2));
    r.cur_min[2][x] = static_cast<std::int16_t>(hmin<B>(m3));
  }
  for (int x = r.hi - 1; x >= r.lo; --x) {
    const std::int16_t* c = r.cost + static_cast<std::size_t>(x) * D;
    std::int16_t* s = r.sum + static_cast<std::size_t>(x) * D;
    const Pred q = x < r.hi - 1 ? Pred{r.horiz_back[(x + 1) & 1], h_min} : Pred{r.start, 0};
    std::int16_t* o = r.horiz_back[x & 1];
    const V pm = V{} + static_cast<std::int16_t>(q.min);
    V m = V{} + kPad;
    for (int d = 0; d < D; d += L) {
      const V v = path_v<B>(q.block, d, pm, p1, p2, load<V>(c + d));
      store(o + 1 + d, v);
      m = vmin(m, v);
      store(s + d, load<V>(s + d) + v);
    }
    h_min = hmin<B>(m);
  }
}

template <int B>
NANEYE_SGM_INLINE void wta_v(const std::int16_t* sum, int D, int dmin, int w, int lo, int hi,
                             std::int16_t* best, std::int16_t* rcost_rev, std::int16_t* rdisp_rev) {
  using V = typename Vec<B>::H;
  constexpr int L = Vec<B>::k16;
  V lane{};
  for (int i = 0; i < L; ++i) lane[i] = static_cast<std::int16_t>(i);
  for (int x = lo; x < hi; ++x) {
    const std::int16_t* s = sum + static_cast<std::size_t>(x) * D;
    std::int16_t* rc = rcost_rev + (w - 1 - x + dmin);
    std::int16_t* rd = rdisp_rev + (w - 1 - x + dmin);
    V m = V{} + sgm_simd::kPad;
    for (int d = 0; d < D; d += L) {
      const V v = load<V>(s + d), c = load<V>(rc + d);
      m = vmin(m, v);
      const auto better = v < c;  // branch-free: which of the right pixels this left pixel improves
      store(rc + d, better ? v : c);
      store(rd + d, better ? lane + static_cast<std::int16_t>(dmin + d) : load<V>(rd + d));
    }
    const int mv = hmin<B>(m);
    int b = 0;
    while (s[b] != mv) ++b;  // the first d at the minimum
    best[x] = static_cast<std::int16_t>(b);
  }
}

void census_sse(const float* img, std::size_t stride, int w, int h, int y, int x0, int x1,
                std::uint32_t* out) {
  census_v<16>(img, stride, w, h, y, x0, x1, out);
}
__attribute__((target("avx2"))) void census_avx2(const float* img, std::size_t stride, int w, int h, int y,
                                                 int x0, int x1, std::uint32_t* out) {
  census_v<32>(img, stride, w, h, y, x0, x1, out);
}
void hamming_sse(const std::uint32_t* cl, const std::uint32_t* cr, int w, int dmin, int D, int x0, int x1,
                 std::int16_t* H) {
  hamming_v<16>(cl, cr, w, dmin, D, x0, x1, H);
}
__attribute__((target("avx2"))) void hamming_avx2(const std::uint32_t* cl, const std::uint32_t* cr, int w,
                                                  int dmin, int D, int x0, int x1, std::int16_t* H) {
  hamming_v<32>(cl, cr, w, dmin, D, x0, x1, H);
}
void hsum3_sse(const std::int16_t* H, int D, int h0, int h1, int x0, int x1, std::int16_t* out) {
  hsum3_v<16>(H, D, h0, h1, x0, x1, out);
}
__attribute__((target("avx2"))) void hsum3_avx2(const std::int16_t* H, int D, int h0, int h1, int x0, int x1,
                                                std::int16_t* out) {
  hsum3_v<32>(H, D, h0, h1, x0, x1, out);
}
void add3_sse(const std::int16_t* a, const std::int16_t* b, const std::int16_t* c, int D, int x0, int x1,
              std::int16_t* out) {
  add3_v<16>(a, b, c, D, x0, x1, out);
}
__attribute__((target("avx2"))) void add3_avx2(const std::int16_t* a, const std::int16_t* b,
                                               const std::int16_t* c, int D, int x0, int x1,
                                               std::int16_t* out) {
  add3_v<32>(a, b, c, D, x0, x1, out);
}
void aggregate_sse(const PathRow& r) {
  aggregate_v<16>(r);
}
__attribute__((target("avx2"))) void aggregate_avx2(const PathRow& r) {
  aggregate_v<32>(r);
}
void wta_sse(const std::int16_t* sum, int D, int dmin, int w, int lo, int hi, std::int16_t* best,
             std::int16_t* rc, std::int16_t* rd) {
  wta_v<16>(sum, D, dmin, w, lo, hi, best, rc, rd);
}
__attribute__((target("avx2"))) void wta_avx2(const std::int16_t* sum, int D, int dmin, int w, int lo, int hi,
                                              std::int16_t* best, std::int16_t* rc, std::int16_t* rd) {
  wta_v<32>(sum, D, dmin, w, lo, hi, best, rc, rd);
}
}  // namespace

Isa best_isa() {
  return __builtin_cpu_supports("avx2") ? Isa::avx2 : Isa::sse2;
}

void census_row(Isa isa, const float* img, std::size_t stride, int w, int h, int y, int x0, int x1,
                std::uint32_t* out) {
  (isa == Isa::avx2   ? census_avx2
   : isa == Isa::sse2 ? census_sse
                      : scalar::census)(img, stride, w, h, y, x0, x1, out);
}

void hamming_row(Isa isa, const std::uint32_t* cl, const std::uint32_t* cr_rev, int w, int dmin, int D,
                 int x0, int x1, std::int16_t* H) {
  (isa == Isa::avx2   ? hamming_avx2
   : isa == Isa::sse2 ? hamming_sse
                      : scalar::hamming)(cl, cr_rev, w, dmin, D, x0, x1, H);
}

void hsum3_row(Isa isa, const std::int16_t* H, int D, int h0, int h1, int x0, int x1, std::int16_t* out) {
  (isa == Isa::avx2 ? hsum3_avx2 : isa == Isa::sse2 ? hsum3_sse : scalar::hsum3)(H, D, h0, h1, x0, x1, out);
}

void add3_row(Isa isa, const std::int16_t* a, const std::int16_t* b, const std::int16_t* c, int D, int x0,
              int x1, std::int16_t* out) {
  (isa == Isa::avx2 ? add3_avx2 : isa == Isa::sse2 ? add3_sse : scalar::add3)(a, b, c, D, x0, x1, out);
}

void aggregate_row(Isa isa, const PathRow& r) {
  (isa == Isa::avx2 ? aggregate_avx2 : isa == Isa::sse2 ? aggregate_sse : scalar::aggregate)(r);
}

void wta_row(Isa isa, const std::int16_t* sum, int D, int dmin, int w, int lo, int hi, std::int16_t* best,
             std::int16_t* rcost_rev, std::int16_t* rdisp_rev) {
  (isa == Isa::avx2   ? wta_avx2
   : isa == Isa::sse2 ? wta_sse
                      : scalar::wta)(sum, D, dmin, w, lo, hi, best, rcost_rev, rdisp_rev);
}

}  // namespace naneye::recon::scene::sgm_simd
