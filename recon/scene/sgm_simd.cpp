// See sgm_simd.hpp: the vector builds and the run-time choice. The scalar reference they are tested
// against is in sgm_scalar.cpp; the vector templates are inlined only into their entry points, each
// compiled for its own target.
#include "sgm_simd.hpp"

#include "sgm_scalar.hpp"

#include <immintrin.h>

#include <algorithm>

#include "../corners/simd.hpp"
#include "sgm_vec.hpp"

namespace naneye::recon::scene::sgm_simd {
namespace {

using namespace vec;
using scalar::kCensusR;

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
    // Unrolled: the 24 comparisons with their loop control were ~1/2 of the census's instructions.
#pragma GCC unroll 5
    for (int dy = -kCensusR; dy <= kCensusR; ++dy)
#pragma GCC unroll 5
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
NANEYE_SGM_INLINE void hamming_v(const std::uint32_t* cl, const std::uint16_t* lo_rev,
                                 const std::uint16_t* hi_rev, int w, int dmin, int D, int x0, int x1,
                                 std::int16_t* H) {
  using UH = typename Vec<B>::UH;
  using V = typename Vec<B>::H;
  constexpr int L = Vec<B>::k16;
  for (int x = x0; x < x1; ++x) {
    const UH llo = UH{} + static_cast<std::uint16_t>(cl[x] & 0xffffu);
    const UH lhi = UH{} + static_cast<std::uint16_t>(cl[x] >> 16);
    const std::size_t j = static_cast<std::size_t>(w - 1 - x + dmin);
    std::int16_t* o = H + static_cast<std::size_t>(x) * D;
    for (int d = 0; d < D; d += L) {  // D is a multiple of 16 (Sgm's constructor)
      // Population count by halving sums (no multiply: SSE2 has no lane product that would help),
      // the low 16 bits and the high 8 side by side until their byte counts (each <= 8) are added.
      UH a = llo ^ load<UH>(lo_rev + j + d), b = lhi ^ load<UH>(hi_rev + j + d);
      a = a - ((a >> 1) & 0x5555);
      b = b - ((b >> 1) & 0x55);
      a = (a & 0x3333) + ((a >> 2) & 0x3333);
      b = (b & 0x33) + ((b >> 2) & 0x33);
      a = ((a + (a >> 4)) & 0x0f0f) + ((b + (b >> 4)) & 0x0f);   // bytes: <= 16 low, <= 8 high
      store(o + d, reinterpret_cast<V>((a + (a >> 8)) & 0x1f));  // <= 24 census bits
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
    // Per lane its minimum and the first d holding it (strictly below: an equal later d does not
    // replace it); the first d at the row's minimum is then the smallest of those indices among the
    // lanes whose minimum it is. One pass over the block (a second one, for the index, cost more).
    V m = V{} + sgm_simd::kPad, at = m, di = lane, dd = lane + static_cast<std::int16_t>(dmin);
    for (int d = 0; d < D; d += L, di += static_cast<std::int16_t>(L), dd += static_cast<std::int16_t>(L)) {
      const V v = load<V>(s + d), c = load<V>(rc + d);
      const auto lower = v < m;
      m = lower ? v : m;
      at = lower ? di : at;
      const auto better = v < c;  // branch-free: which of the right pixels this left pixel improves
      store(rc + d, better ? v : c);
      store(rd + d, better ? dd : load<V>(rd + d));
    }
    const V mv = V{} + static_cast<std::int16_t>(hmin<B>(m));
    best[x] = static_cast<std::int16_t>(hmin<B>(m == mv ? at : V{} + sgm_simd::kPad));
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
void hamming_sse(const std::uint32_t* cl, const std::uint16_t* lo, const std::uint16_t* hi, int w, int dmin,
                 int D, int x0, int x1, std::int16_t* H) {
  hamming_v<16>(cl, lo, hi, w, dmin, D, x0, x1, H);
}
// AVX2 has a byte shuffle: the population count by a 16-entry table of nibble counts (the low 16
// bits' four nibbles and the high 8 bits' two, moved to the lane's two bytes), the bytes then added
// in pairs. 18 instructions per 16 disparities where the halving sums took 29; the same counts.
__attribute__((target("avx2"))) void hamming_avx2(const std::uint32_t* cl, const std::uint16_t* lo_rev,
                                                  const std::uint16_t* hi_rev, int w, int dmin, int D, int x0,
                                                  int x1, std::int16_t* H) {
  const __m256i table = _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4, 0, 1, 1, 2, 1, 2, 2,
                                         3, 1, 2, 2, 3, 2, 3, 3, 4);
  const __m256i nib = _mm256_set1_epi16(0x0f0f), low = _mm256_set1_epi16(0x000f),
                high = _mm256_set1_epi16(0x0f00);
  const __m256i ones = _mm256_set1_epi8(1);
  for (int x = x0; x < x1; ++x) {
    const __m256i llo = _mm256_set1_epi16(static_cast<std::int16_t>(cl[x] & 0xffffu));
    const __m256i lhi = _mm256_set1_epi16(static_cast<std::int16_t>(cl[x] >> 16));
    const std::size_t j = static_cast<std::size_t>(w - 1 - x + dmin);
    std::int16_t* o = H + static_cast<std::size_t>(x) * D;
    for (int d = 0; d < D; d += 16) {
      const __m256i a =
          _mm256_xor_si256(llo, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(lo_rev + j + d)));
      const __m256i b =
          _mm256_xor_si256(lhi, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(hi_rev + j + d)));
      const __m256i bn =
          _mm256_or_si256(_mm256_and_si256(b, low), _mm256_and_si256(_mm256_slli_epi16(b, 4), high));
      const __m256i n = _mm256_add_epi8(
          _mm256_add_epi8(_mm256_shuffle_epi8(table, _mm256_and_si256(a, nib)),
                          _mm256_shuffle_epi8(table, _mm256_and_si256(_mm256_srli_epi16(a, 4), nib))),
          _mm256_shuffle_epi8(table, bn));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(o + d), _mm256_maddubs_epi16(n, ones));
    }
  }
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
  return simd::has_avx2() ? Isa::avx2 : Isa::sse2;
}

void census_row(Isa isa, const float* img, std::size_t stride, int w, int h, int y, int x0, int x1,
                std::uint32_t* out) {
  (isa == Isa::avx2   ? census_avx2
   : isa == Isa::sse2 ? census_sse
                      : scalar::census)(img, stride, w, h, y, x0, x1, out);
}

void hamming_row(Isa isa, const std::uint32_t* cl, const std::uint16_t* lo_rev, const std::uint16_t* hi_rev,
                 int w, int dmin, int D, int x0, int x1, std::int16_t* H) {
  (isa == Isa::avx2   ? hamming_avx2
   : isa == Isa::sse2 ? hamming_sse
                      : scalar::hamming)(cl, lo_rev, hi_rev, w, dmin, D, x0, x1, H);
}

void hsum3_row(Isa isa, const std::int16_t* H, int D, int h0, int h1, int x0, int x1, std::int16_t* out) {
  (isa == Isa::avx2 ? hsum3_avx2 : isa == Isa::sse2 ? hsum3_sse : scalar::hsum3)(H, D, h0, h1, x0, x1, out);
}

void add3_row(Isa isa, const std::int16_t* a, const std::int16_t* b, const std::int16_t* c, int D, int x0,
              int x1, std::int16_t* out) {
  (isa == Isa::avx2 ? add3_avx2 : isa == Isa::sse2 ? add3_sse : scalar::add3)(a, b, c, D, x0, x1, out);
}

void wta_row(Isa isa, const std::int16_t* sum, int D, int dmin, int w, int lo, int hi, std::int16_t* best,
             std::int16_t* rcost_rev, std::int16_t* rdisp_rev) {
  (isa == Isa::avx2   ? wta_avx2
   : isa == Isa::sse2 ? wta_sse
                      : scalar::wta)(sum, D, dmin, w, lo, hi, best, rcost_rev, rdisp_rev);
}

}  // namespace naneye::recon::scene::sgm_simd
