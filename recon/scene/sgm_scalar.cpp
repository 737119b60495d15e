// See sgm_scalar.hpp: the plain loops, the reference of every vector build (sgm_simd.cpp).
#include "sgm_scalar.hpp"

#include <algorithm>

namespace naneye::recon::scene::sgm_simd::scalar {
namespace {

std::uint32_t census_at(const float* img, std::size_t stride, int x, int y) {
  const float* c = img + static_cast<std::size_t>(y) * stride + x;
  std::uint32_t bits = 0, bit = 1;
  for (int dy = -kCensusR; dy <= kCensusR; ++dy)
    for (int dx = -kCensusR; dx <= kCensusR; ++dx) {
      if (dy == 0 && dx == 0) continue;
      if (c[dy * static_cast<std::ptrdiff_t>(stride) + dx] > *c) bits |= bit;
      bit <<= 1;
    }
  return bits;
}

// Hirschmueller 2008, Eq. 13: L_r(p, d) = C(p, d) + min(L_r(p - r, d), L_r(p - r, d - 1) + P1,
// L_r(p - r, d + 1) + P1, min_i L_r(p - r, i) + P2) - min_k L_r(p - r, k). `prev` is the
// predecessor's padded block, `out` this pixel's; returns min_d of the new values.
int path(const std::int16_t* prev, int prev_min, const std::int16_t* c, std::int16_t* out, int D, int p1,
         int p2) {
  int m = kPad;
  for (int d = 0; d < D; ++d) {
    const int best = std::min({static_cast<int>(prev[1 + d]), prev[d] + p1, prev[2 + d] + p1, prev_min + p2});
    const int v = c[d] + best - prev_min;
    out[1 + d] = static_cast<std::int16_t>(v);
    m = std::min(m, v);
  }
  return m;
}

}  // namespace

void census(const float* img, std::size_t stride, int w, int h, int y, int x0, int x1, std::uint32_t* out) {
  const bool row_in = y >= kCensusR && y < h - kCensusR;
  for (int x = x0; x < x1; ++x)
    out[x] = row_in && x >= kCensusR && x < w - kCensusR ? census_at(img, stride, x, y) : 0u;
}

void hamming(const std::uint32_t* cl, const std::uint16_t* lo_rev, const std::uint16_t* hi_rev, int w,
             int dmin, int D, int x0, int x1, std::int16_t* H) {
  for (int x = x0; x < x1; ++x)
    for (int d = 0; d < D; ++d) {
      const std::size_t j = static_cast<std::size_t>(w - 1 - x + dmin + d);
      const std::uint32_t cr = lo_rev[j] | static_cast<std::uint32_t>(hi_rev[j]) << 16;
      H[static_cast<std::size_t>(x) * D + d] = static_cast<std::int16_t>(__builtin_popcount(cl[x] ^ cr));
    }
}

void hsum3(const std::int16_t* H, int D, int h0, int h1, int x0, int x1, std::int16_t* out) {
  for (int x = x0; x < x1; ++x) {
    const std::int16_t* a = H + static_cast<std::size_t>(std::max(h0, x - 1)) * D;
    const std::int16_t* b = H + static_cast<std::size_t>(x) * D;
    const std::int16_t* c = H + static_cast<std::size_t>(std::min(h1 - 1, x + 1)) * D;
    for (int d = 0; d < D; ++d)
      out[static_cast<std::size_t>(x) * D + d] = static_cast<std::int16_t>(a[d] + b[d] + c[d]);
  }
}

void add3(const std::int16_t* a, const std::int16_t* b, const std::int16_t* c, int D, int x0, int x1,
          std::int16_t* out) {
  for (std::size_t i = static_cast<std::size_t>(x0) * D; i < static_cast<std::size_t>(x1) * D; ++i)
    out[i] = static_cast<std::int16_t>(a[i] + b[i] + c[i]);
}

void aggregate(const PathRow& r) {
  const int D = r.D, Ds = D + 2;
  int h_min = 0;
  for (int x = r.lo; x < r.hi; ++x) {
    const std::int16_t* c = r.cost + static_cast<std::size_t>(x) * D;
    std::int16_t* s = r.sum + static_cast<std::size_t>(x) * D;
    const Pred h = x > r.lo ? Pred{r.horiz[(x - 1) & 1], h_min} : Pred{r.start, 0};
    h_min = path(h.block, h.min, c, r.horiz[x & 1], D, r.p1, r.p2);
    for (int d = 0; d < D; ++d) s[d] = r.horiz[x & 1][1 + d];
    for (int k = 0; k < 3; ++k) {
      const Pred p = above(r, k, x - 1 + k);  // top-left, top, top-right
      std::int16_t* o = r.cur[k] + static_cast<std::size_t>(x) * Ds;
      r.cur_min[k][x] = static_cast<std::int16_t>(path(p.block, p.min, c, o, D, r.p1, r.p2));
      for (int d = 0; d < D; ++d) s[d] = static_cast<std::int16_t>(s[d] + o[1 + d]);
    }
  }
  for (int x = r.hi - 1; x >= r.lo; --x) {
    const std::int16_t* c = r.cost + static_cast<std::size_t>(x) * D;
    std::int16_t* s = r.sum + static_cast<std::size_t>(x) * D;
    const Pred h = x < r.hi - 1 ? Pred{r.horiz_back[(x + 1) & 1], h_min} : Pred{r.start, 0};
    h_min = path(h.block, h.min, c, r.horiz_back[x & 1], D, r.p1, r.p2);
    for (int d = 0; d < D; ++d) s[d] = static_cast<std::int16_t>(s[d] + r.horiz_back[x & 1][1 + d]);
  }
}

void wta(const std::int16_t* sum, int D, int dmin, int w, int lo, int hi, std::int16_t* best,
         std::int16_t* rcost_rev, std::int16_t* rdisp_rev) {
  for (int x = lo; x < hi; ++x) {
    const std::int16_t* s = sum + static_cast<std::size_t>(x) * D;
    int b = 0;
    for (int d = 1; d < D; ++d)
      if (s[d] < s[b]) b = d;
    best[x] = static_cast<std::int16_t>(b);
    const std::size_t j = static_cast<std::size_t>(w - 1 - x + dmin);  // right pixel x - dmin - d at j + d
    for (int d = 0; d < D; ++d)
      if (s[d] < rcost_rev[j + d]) {
        rcost_rev[j + d] = s[d];
        rdisp_rev[j + d] = static_cast<std::int16_t>(dmin + d);
      }
  }
}

}  // namespace naneye::recon::scene::sgm_simd::scalar
