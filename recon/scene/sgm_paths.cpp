// The semi-global matcher's path kernel (sgm_simd.hpp's aggregate_row), its vector builds: Eq. 13
// of Hirschmueller 2008 along the five paths of one row, and S (Eq. 14). The scalar reference is
// sgm_scalar.cpp's aggregate; every build gives its bits (SgmKernels.*).
#include <algorithm>
#include <cstddef>

#include "sgm_scalar.hpp"
#include "sgm_simd.hpp"
#include "sgm_vec.hpp"

namespace naneye::recon::scene::sgm_simd {
namespace {

using namespace vec;
using scalar::above;
using scalar::Pred;

// Eq. 13 on L disparities from d, the predecessor in memory (the paths from the row above):
// L_r(p, d) = C(p, d) + min(L_r(p - r, d), L_r(p - r, d -+ 1) + P1, min_k L_r(p - r, k) + P2)
// - min_k L_r(p - r, k); jump = prev_min + P2 is formed here rather than kept per path (four fewer
// live registers in the forward loop).
template <int B>
NANEYE_SGM_INLINE typename Vec<B>::H path_v(const std::int16_t* prev, int d,
                                            const typename Vec<B>::H& prev_min, const typename Vec<B>::H& p1,
                                            const typename Vec<B>::H& p2, const typename Vec<B>::H& c) {
  using V = typename Vec<B>::H;
  const V a = load<V>(prev + 1 + d), lo = load<V>(prev + d) + p1, hi = load<V>(prev + 2 + d) + p1;
  return vmin(vmin(a, lo), vmin(hi, prev_min + p2)) + c - prev_min;
}

// Eq. 13 with the predecessor's values in registers (the horizontal paths): `a` its values at
// d .. d + L - 1, `below` those at d - L .. d - 1 and `above` at d + L .. (kPad beyond the band).
// Its neighbours at d -+ 1 are lane shifts (vperm2i128 + vpalignr with AVX2) rather than loads
// straddling the stores of the pixel just done, which the store buffer cannot forward.
template <int B>
NANEYE_SGM_INLINE typename Vec<B>::H path_reg(const typename Vec<B>::H& below, const typename Vec<B>::H& a,
                                              const typename Vec<B>::H& above,
                                              const typename Vec<B>::H& prev_min,
                                              const typename Vec<B>::H& p1, const typename Vec<B>::H& p2,
                                              const typename Vec<B>::H& c) {
  using V = typename Vec<B>::H;
  V lo, hi;
  if constexpr (B == 32) {
    lo = __builtin_shuffle(below, a, V{15, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30});
    hi = __builtin_shuffle(a, above, V{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16});
  } else {
    lo = __builtin_shuffle(below, a, V{7, 8, 9, 10, 11, 12, 13, 14});
    hi = __builtin_shuffle(a, above, V{1, 2, 3, 4, 5, 6, 7, 8});
  }
  return vmin(vmin(a, lo + p1), vmin(hi + p1, prev_min + p2)) + c - prev_min;
}

// The predecessor's block k + 1, kPad beyond the band (the index stays in bounds for any k < N).
template <int N, class V>
NANEYE_SGM_INLINE V next(const V (&h)[N], int k, const V& pad) {
  return k + 1 < N ? h[k + 1 < N ? k + 1 : k] : pad;
}

// A band of N vectors (D = N L, known when compiled): both horizontal paths' predecessors stay in
// registers, h[k] holding d = k L .. k L + L - 1; the three paths from the row above are read from
// their row buffers, their four minima (with the forward one) reduced together (hmin4). The
// horizontal paths' values are not stored: nothing reads them but the next pixel.
template <int B, int N>
NANEYE_SGM_INLINE void aggregate_fixed(const PathRow& r) {
  using V = typename Vec<B>::H;
  constexpr int L = Vec<B>::k16, D = N * L;
  constexpr std::size_t Ds = D + 2;
  const V p1 = V{} + r.p1, p2 = V{} + r.p2, pad = V{} + kPad;
  V h[N];
  for (int k = 0; k < N; ++k) h[k] = V{};  // a path's first pixel: the zero start block
  int h_min = 0;
  auto forward = [&](int x, const Pred& q1, const Pred& q2, const Pred& q3) __attribute__((always_inline)) {
    const std::int16_t* c = r.cost + static_cast<std::size_t>(x) * D;
    std::int16_t* s = r.sum + static_cast<std::size_t>(x) * D;
    std::int16_t* o1 = r.cur[0] + static_cast<std::size_t>(x) * Ds;
    std::int16_t* o2 = r.cur[1] + static_cast<std::size_t>(x) * Ds;
    std::int16_t* o3 = r.cur[2] + static_cast<std::size_t>(x) * Ds;
    const V pm0 = V{} + static_cast<std::int16_t>(h_min), pm1 = V{} + static_cast<std::int16_t>(q1.min);
    const V pm2 = V{} + static_cast<std::int16_t>(q2.min), pm3 = V{} + static_cast<std::int16_t>(q3.min);
    V m0 = pad, m1 = pad, m2 = pad, m3 = pad, below = pad;  // below: the predecessor's block k - 1
#pragma GCC unroll 16
    for (int k = 0; k < N; ++k) {
      const int d = k * L;
      const V cv = load<V>(c + d);
      const V v0 = path_reg<B>(below, h[k], next(h, k, pad), pm0, p1, p2, cv);
      const V v1 = path_v<B>(q1.block, d, pm1, p1, p2, cv);
      const V v2 = path_v<B>(q2.block, d, pm2, p1, p2, cv);
      const V v3 = path_v<B>(q3.block, d, pm3, p1, p2, cv);
      below = h[k];
      h[k] = v0;
      store(o1 + 1 + d, v1);
      store(o2 + 1 + d, v2);
      store(o3 + 1 + d, v3);
      m0 = vmin(m0, v0);
      m1 = vmin(m1, v1);
      m2 = vmin(m2, v2);
      m3 = vmin(m3, v3);
      store(s + d, (v0 + v1) + (v2 + v3));  // exact in int16 (S < kPad): any order gives the same bits
    }
    int mins[4];
    hmin4<B>(m0, m1, m2, m3, mins);
    h_min = mins[0];
    for (int k = 0; k < 3; ++k) r.cur_min[k][x] = static_cast<std::int16_t>(mins[1 + k]);
  };
  // Where all three predecessors lie inside the row above's span, above()'s range tests are known
  // to pass (they were ~3 M instructions a pair): the row is done in three parts.
  auto inner = [&](int k, int xp) __attribute__((always_inline)) {
    return Pred{r.prev[k] + static_cast<std::size_t>(xp) * Ds, r.prev_min[k][xp]};
  };
  const int in0 = std::clamp(r.prev_lo + 1, r.lo, r.hi), in1 = std::clamp(r.prev_hi - 1, in0, r.hi);
  int x = r.lo;
  for (; x < in0; ++x) forward(x, above(r, 0, x - 1), above(r, 1, x), above(r, 2, x + 1));
  for (; x < in1; ++x) forward(x, inner(0, x - 1), inner(1, x), inner(2, x + 1));
  for (; x < r.hi; ++x) forward(x, above(r, 0, x - 1), above(r, 1, x), above(r, 2, x + 1));
  for (int k = 0; k < N; ++k) h[k] = V{};
  h_min = 0;
  for (int x = r.hi - 1; x >= r.lo; --x) {
    const std::int16_t* c = r.cost + static_cast<std::size_t>(x) * D;
    std::int16_t* s = r.sum + static_cast<std::size_t>(x) * D;
    const V pm = V{} + static_cast<std::int16_t>(h_min);
    V m = pad, below = pad;
#pragma GCC unroll 16
    for (int k = 0; k < N; ++k) {
      const int d = k * L;
      const V v = path_reg<B>(below, h[k], next(h, k, pad), pm, p1, p2, load<V>(c + d));
      below = h[k];
      h[k] = v;
      m = vmin(m, v);
      store(s + d, load<V>(s + d) + v);
    }
    h_min = hmin<B>(m);
  }
}

// Any band (D a multiple of 16): every predecessor in memory, the horizontal ones in r.horiz.
template <int B>
NANEYE_SGM_INLINE void aggregate_any(const PathRow& r) {
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
      store(s + d, (v0 + v1) + (v2 + v3));
    }
    int mins[4];
    hmin4<B>(m0, m1, m2, m3, mins);
    h_min = mins[0];
    for (int k = 0; k < 3; ++k) r.cur_min[k][x] = static_cast<std::int16_t>(mins[1 + k]);
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

// The bands the dense path uses (48 px: z 8-80 mm at f B = 235.5 px mm) and their neighbours
// (16-64 px) are compiled with their length; any other takes the general loop. D is a multiple of
// 16 (Sgm's constructor asserts it).
template <int B>
NANEYE_SGM_INLINE void aggregate_band(const PathRow& r) {
  constexpr int per16 = 16 / Vec<B>::k16;  // vectors per 16 disparities
  switch (r.D / 16) {
    case 1:
      return aggregate_fixed<B, per16>(r);
    case 2:
      return aggregate_fixed<B, 2 * per16>(r);
    case 3:
      return aggregate_fixed<B, 3 * per16>(r);
    case 4:
      return aggregate_fixed<B, 4 * per16>(r);
    default:
      return aggregate_any<B>(r);
  }
}
void aggregate_sse(const PathRow& r) {
  aggregate_band<16>(r);
}
__attribute__((target("avx2"))) void aggregate_avx2(const PathRow& r) {
  aggregate_band<32>(r);
}

}  // namespace

void aggregate_row(Isa isa, const PathRow& r) {
  (isa == Isa::avx2 ? aggregate_avx2 : isa == Isa::sse2 ? aggregate_sse : scalar::aggregate)(r);
}

}  // namespace naneye::recon::scene::sgm_simd
