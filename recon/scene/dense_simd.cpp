// See dense_simd.hpp. The vector helpers are corners/simd.hpp's (inlined only into the entry points
// below, each compiled for its own target).
#include "dense_simd.hpp"

#include <algorithm>

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
template <class V>
NANEYE_SIMD_INLINE void box_sum_v(const float* __restrict in, float* __restrict out, float* __restrict tmp,
                                  const Spans& sp, int r) {
  constexpr int L = kLanes<V>;
  const int w = sp.w, h = sp.h;
  const int inner0 = std::min(r, w), inner1 = std::max(inner0, w - r);
  for (int y = 0; y < h; ++y) {
    const int lo = sp.lo[y], hi = sp.hi[y];
    if (lo >= hi) continue;
    const int c0 = std::max(0, lo - r), c1 = std::min(w, hi + r);
    const int y0 = std::max(0, y - r), y1 = std::min(h - 1, y + r);
    const float* first = in + static_cast<std::size_t>(y0) * w;
    int x = c0;
    for (; x + L <= c1; x += L) {
      V acc = load<V>(first + x);
      for (int yy = y0 + 1; yy <= y1; ++yy) acc += load<V>(in + static_cast<std::size_t>(yy) * w + x);
      store(tmp + x, acc);
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
      for (int k = 1 - r; k <= r; ++k) acc += load<V>(tmp + x + k);
      store(o + x, acc);
    }
    for (; x < i1; ++x) {
      float acc = tmp[x - r];
      for (int k = 1 - r; k <= r; ++k) acc += tmp[x + k];
      o[x] = acc;
    }
    for (x = std::max(lo, inner1); x < hi; ++x) edge(x);
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

void box_sum_sse(const float* in, float* out, float* tmp, const Spans& sp, int r) {
  box_sum_v<simd::V4>(in, out, tmp, sp, r);
}
__attribute__((target("avx2"))) void box_sum_avx2(const float* in, float* out, float* tmp, const Spans& sp,
                                                  int r) {
  box_sum_v<simd::V8>(in, out, tmp, sp, r);
}
void filter_lags_sse(const float* z, float* out, const float* rho, int lag, const Spans& sp) {
  filter_lags_v<simd::V4>(z, out, rho, lag, sp);
}
__attribute__((target("avx2"))) void filter_lags_avx2(const float* z, float* out, const float* rho, int lag,
                                                      const Spans& sp) {
  filter_lags_v<simd::V8>(z, out, rho, lag, sp);
}
}  // namespace

bool avx2_available() {
  return __builtin_cpu_supports("avx2");
}

void box_sum(bool avx2, const float* in, float* out, float* tmp, const Spans& sp, int r) {
  (avx2 ? box_sum_avx2 : box_sum_sse)(in, out, tmp, sp, r);
}

void filter_lags(bool avx2, const float* z, float* out, const float* rho, int lag, const Spans& sp) {
  (avx2 ? filter_lags_avx2 : filter_lags_sse)(z, out, rho, lag, sp);
}

}  // namespace naneye::recon::scene::dense_simd

#pragma GCC diagnostic pop
