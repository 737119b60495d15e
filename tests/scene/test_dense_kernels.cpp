// The dense path's vector kernels (recon/scene/dense_simd.hpp) and its median selection
// (recon/scene/select.hpp): the 4-lane (SSE2) and 8-lane (AVX2, when this CPU has it) builds give
// the plain scalar loops' bits, and kth_smallest gives std::nth_element's value. The dense maps
// therefore do not depend on the machine they are computed on.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "../../recon/corners/simd.hpp"
#include "../../recon/scene/dense_simd.hpp"
#include "../../recon/scene/select.hpp"

namespace naneye::recon::scene {
namespace {

std::vector<bool> dense_kernel_builds() {
  std::vector<bool> b{false};
  if (simd::has_avx2()) b.push_back(true);
  return b;
}

// A w x h plane with data only inside random row spans (zero elsewhere), as the matcher keeps it.
struct SpanPlane {
  int w = 61, h = 23;  // odd sizes: every vector loop has a scalar tail
  std::vector<int> lo, hi;
  std::vector<float> v;
  explicit SpanPlane(std::mt19937& rng) : lo(static_cast<std::size_t>(h)), hi(static_cast<std::size_t>(h)) {
    std::uniform_int_distribution<int> col(0, w);
    std::uniform_real_distribution<float> val(-300.f, 300.f);
    v.assign(static_cast<std::size_t>(w) * h, 0.f);
    for (std::size_t y = 0; y < lo.size(); ++y) {
      lo[y] = col(rng);
      hi[y] = std::max(lo[y], col(rng));
      if (y % 7 == 3) lo[y] = hi[y] = 0;  // rows without data
      for (int x = lo[y]; x < hi[y]; ++x)
        v[y * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)] = val(rng);
    }
  }
  dense_simd::Spans spans() const { return {lo.data(), hi.data(), w, h}; }
  float at(int x, int y) const {
    return x < 0 || y < 0 || x >= w || y >= h
               ? 0.f
               : v[static_cast<std::size_t>(y) * w + static_cast<std::size_t>(x)];
  }
};

TEST(DenseKernels, BoxSumGivesTheScalarSumsBits) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 36; ++trial) {
    const SpanPlane p(rng);
    // 3, 4, 5, 6, 8, 10, 12 have their own unrolled kernels (the matcher's radii and twice them), 2
    // and 7 the general one.
    constexpr int kRadii[] = {2, 3, 4, 5, 6, 7, 8, 10, 12};
    const int r = kRadii[trial % 9];
    for (const bool avx2 : dense_kernel_builds()) {
      std::vector<float> out(p.v.size(), -1.f), tmp(static_cast<std::size_t>(p.w));
      dense_simd::box_sum(avx2, p.v.data(), out.data(), tmp.data(), p.spans(), r);
      for (int y = 0; y < p.h; ++y)
        for (int x = p.lo[static_cast<std::size_t>(y)]; x < p.hi[static_cast<std::size_t>(y)]; ++x) {
          // Rows top to bottom into each column, then the columns left to right.
          float s = 0;
          bool first = true;
          for (int k = std::max(0, x - r); k <= std::min(p.w - 1, x + r); ++k) {
            float col = p.at(k, std::max(0, y - r));
            for (int yy = std::max(0, y - r) + 1; yy <= std::min(p.h - 1, y + r); ++yy) col += p.at(k, yy);
            // The inner columns start from the first column's sum, the edges from 0 (both exact).
            s = first ? col : s + col;
            first = false;
          }
          ASSERT_EQ(out[static_cast<std::size_t>(y) * p.w + static_cast<std::size_t>(x)], s)
              << (avx2 ? "avx2 " : "sse ") << "r " << r << " at " << x << ", " << y;
        }
    }
  }
}

TEST(DenseKernels, LagFilterGivesTheScalarLoopsBits) {
  std::mt19937 rng(4);
  std::vector<float> rho(49);
  std::uniform_real_distribution<float> r(-1.f, 1.f);
  for (auto& x : rho) x = r(rng);
  for (int trial = 0; trial < 10; ++trial) {
    const SpanPlane p(rng);
    for (const bool avx2 : dense_kernel_builds()) {
      std::vector<float> out(p.v.size(), 0.f);
      dense_simd::filter_lags(avx2, p.v.data(), out.data(), rho.data(), 3, p.spans());
      for (int y = 0; y < p.h; ++y)
        for (int x = p.lo[static_cast<std::size_t>(y)]; x < p.hi[static_cast<std::size_t>(y)]; ++x) {
          float s = 0;
          for (int dy = -3; dy <= 3; ++dy)
            for (int dx = -3; dx <= 3; ++dx)
              if (y + dy >= 0 && y + dy < p.h && x + dx >= 0 && x + dx < p.w)
                s += rho[static_cast<std::size_t>((dy + 3) * 7 + dx + 3)] * p.at(x + dx, y + dy);
          ASSERT_EQ(out[static_cast<std::size_t>(y) * p.w + static_cast<std::size_t>(x)], s)
              << (avx2 ? "avx2 " : "sse ") << x << ", " << y;
        }
    }
  }
}

TEST(DenseKernels, GatherGivesTheScalarLoopsBits) {
  std::mt19937 rng(5);
  constexpr int w = 83;
  std::uniform_real_distribution<float> val(0.f, 900.f), disp(-2.f, 30.f);
  std::vector<float> left(w), right(w), grad(w), d(w);
  std::vector<std::uint8_t> valid(w), ok(w);
  for (int x = 0; x < w; ++x) {
    left[x] = val(rng);
    right[x] = val(rng);
    grad[x] = x % 23 == 4 ? NAN : val(rng) - 450.f;  // NaN: the left has no gradient there
    d[x] = x % 11 == 5 ? NAN : disp(rng);
    // Infinite references fail the AVX2 build's range test on the floor, as isfinite does.
    if (x % 13 == 7) d[x] = x % 2 ? INFINITY : -INFINITY;
    // Finite but beyond int's range once floored: both builds' conversions refuse them.
    if (x % 19 == 2) d[x] = x % 2 ? 3e9f : -3e9f;
    valid[x] = x % 17 != 9;
  }
  for (int x = 0; x < w; ++x)
    ok[x] = x >= 1 && x + 2 < w && valid[x - 1] && valid[x] && valid[x + 1] && valid[x + 2];
  const float mu = 412.5f;
  for (const bool avx2 : dense_kernel_builds()) {
    std::vector<float> ch(10 * w, -1.f);
    dense_simd::GatherRow g{};
    g.left = left.data();
    g.left_grad = grad.data();
    g.right = right.data();
    g.taps_ok = ok.data();
    g.d = d.data();
    for (int k = 0; k < 10; ++k) g.ch[k] = ch.data() + k * w;
    g.lo = 3;
    g.hi = w - 1;
    g.w = w;
    g.mu = mu;
    dense_simd::gather_row(avx2, g);
    for (int x = g.lo; x < g.hi; ++x) {
      float m = 0, W = 0, G = 0, l = 0;
      if (std::isfinite(d[x])) {
        const float xs = static_cast<float>(x) - d[x];
        const int i0 = static_cast<int>(std::floor(xs));
        if (i0 >= 1 && i0 + 2 < w && ok[i0] && std::isfinite(grad[x])) {
          // The cubic B-spline's weights (the row holds its coefficients).
          const float t = xs - static_cast<float>(i0), t2 = t * t, t3 = t2 * t, s = 1.f - t;
          const float wk[4] = {(1.f / 6.f) * (s * s * s), 0.5f * t3 - t2 + 2.f / 3.f,
                               -0.5f * t3 + 0.5f * t2 + 0.5f * t + 1.f / 6.f, (1.f / 6.f) * t3};
          for (int k = 0; k < 4; ++k) W += wk[k] * (right[i0 - 1 + k] - mu);
          G = grad[x];
          l = left[x] - mu;
          m = 1;
        }
      }
      const float want[10] = {m,         m * W,     m * l,     m * G,     m * W * W,
                              m * G * G, m * W * G, m * W * l, m * G * l, m * l * l};
      for (int k = 0; k < 10; ++k)
        ASSERT_EQ(ch[k * w + x], want[k]) << (avx2 ? "avx2 " : "sse ") << x << " ch " << k;
    }
    EXPECT_EQ(ch[0 * w + 2], -1.f);  // outside [lo, hi): untouched
    EXPECT_EQ(ch[0 * w + w - 1], -1.f);
  }
}

// The earlier iterations' step (RectifiedMatcher::refine) against the plain float loop: every
// refusal (no disparity, an infinite one, no data, N < 4, det <= 0, na <= 0), clamped and free
// steps, odd spans (the vector tail).
TEST(DenseKernels, StepRowGivesTheScalarLoopsBits) {
  std::mt19937 rng(9);
  constexpr int w = 45;
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  for (int trial = 0; trial < 40; ++trial) {
    std::vector<float> S(9 * w), m(w), d(w);
    for (int x = 0; x < w; ++x) {
      const float N = static_cast<float>(rng() % 50), mw = 40 * u(rng), mg = 30 * u(rng), ml = 40 * u(rng);
      S[0 * w + x] = N;
      S[1 * w + x] = N * mw;
      S[2 * w + x] = N * ml;
      S[3 * w + x] = N * mg;
      // Centred sums of squares around 100-900, cross terms that sometimes make det <= 0.
      const float ww = 500 + 400 * u(rng), gg = 500 + 400 * u(rng), wg = 700 * u(rng);
      S[4 * w + x] = ww + N * mw * mw;
      S[5 * w + x] = gg + N * mg * mg;
      S[6 * w + x] = wg + N * mw * mg;
      S[7 * w + x] = 300 * u(rng) + N * mw * ml;
      S[8 * w + x] = 300 * u(rng) + N * mg * ml;
      m[x] = x % 9 == 4 ? 0.f : 1.f;
      d[x] = x % 11 == 3 ? NAN : x % 13 == 6 ? INFINITY : 20 * u(rng);
    }
    const int lo = static_cast<int>(rng() % 10), hi = lo + static_cast<int>(rng() % (w - lo + 1));
    for (const bool avx2 : dense_kernel_builds()) {
      std::vector<float> dk = d, out(w, -1.f), solved(w, -1.f);
      dense_simd::StepRow r{};
      for (int k = 0; k < 9; ++k) r.s[k] = S.data() + k * w;
      r.m = m.data();
      r.d = dk.data();
      r.out = out.data();
      r.solved = solved.data();
      r.lo = lo;
      r.hi = hi;
      dense_simd::step_row(avx2, r);
      for (int x = 0; x < w; ++x) {
        float want_d = d[x], want_out = 0, want_solved = 0;
        const float* s = &S[x];
        const float N = s[0], sw = s[w], sl = s[2 * w], sg = s[3 * w], inv = 1.f / N;
        const float Sww = s[4 * w] - sw * sw * inv, Sgg = s[5 * w] - sg * sg * inv;
        const float Swg = s[6 * w] - sw * sg * inv, Swl = s[7 * w] - sw * sl * inv;
        const float Sgl = s[8 * w] - sg * sl * inv;
        const float det = Sww * Sgg - Swg * Swg, na = Sgg * Swl - Swg * Sgl, nc = Swg * Swl - Sww * Sgl;
        if (x < lo || x >= hi) {
          want_out = want_solved = -1;  // outside the span: untouched
        } else if (!std::isfinite(d[x]) || m[x] == 0 || N < 4 || !(det > 0)) {
          want_d = NAN;
        } else if (na > 0) {
          want_out = d[x] + std::clamp(nc / det, -0.5f, 0.5f);
          want_solved = 1;
        }
        const char* b = avx2 ? "avx2 " : "sse ";
        ASSERT_EQ(out[x], want_out) << b << x;
        ASSERT_EQ(solved[x], want_solved) << b << x;
        if (std::isnan(want_d))
          ASSERT_TRUE(std::isnan(dk[x])) << b << x;
        else
          ASSERT_EQ(dk[x], want_d) << b << x;
      }
    }
  }
}

// The residual's lag sums against the plain loop (the matcher's before 2026-12-04 night), on odd
// sizes whose last row's last pixel makes the 8-float block leave the plane.
TEST(DenseKernels, LagProductsGiveThePlainLoopsBits) {
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> u(-3.f, 3.f);
  for (const int w : {11, 16, 37}) {
    const int h = w - 2;
    std::vector<float> e(static_cast<std::size_t>(w) * h);
    for (std::size_t i = 0; i < e.size(); ++i) e[i] = i % 5 == 2 ? 0.f : u(rng);
    double want[7][7] = {};
    for (int y = 3; y < h - 3; y += 2)
      for (int x = 3; x < w - 3; x += 2) {
        const float ei = e[static_cast<std::size_t>(y) * w + x];
        if (ei == 0) continue;
        for (int dy = -3; dy <= 3; ++dy)
          for (int dx = -3; dx <= 3; ++dx)
            want[dy + 3][dx + 3] += ei * e[static_cast<std::size_t>(y + dy) * w + x + dx];
      }
    for (const bool avx2 : dense_kernel_builds()) {
      double acc[49];
      dense_simd::lag_products(avx2, e.data(), w, h, acc);
      for (int k = 0; k < 49; ++k)
        ASSERT_EQ(acc[k], want[k / 7][k % 7]) << (avx2 ? "avx2 " : "sse ") << w << " " << k;
    }
  }
}

TEST(DenseKernels, KthSmallestIsNthElementsValue) {
  std::mt19937 rng(6);
  SelectHistogram hist;
  for (int trial = 0; trial < 50; ++trial) {
    const std::size_t n = 1 + rng() % 5000;
    std::vector<float> v(n);
    std::lognormal_distribution<float> ln(0.f, 1.5f);
    for (auto& x : v) {
      x = ln(rng);
      if (rng() % 10 == 0) x = 0.f;                    // zeros
      if (rng() % 10 == 1) x = std::round(x * 4) / 4;  // ties
      if (rng() % 50 == 2) x = -0.f;                   // as std::max(0, -0) can give
    }
    const std::size_t k = trial % 3 == 0 ? n / 2 : rng() % n;
    std::vector<float> a = v, b = v;
    std::nth_element(a.begin(), a.begin() + static_cast<long>(k), a.end());
    EXPECT_EQ(kth_smallest(b.data(), n, k, hist), a[k]) << n << " " << k;
    // Two ranks from one count (level_medians: the median and the lower quantile), either order.
    const std::size_t k2 = rng() % n;
    std::vector<float> c = v, a2 = v;
    std::nth_element(a2.begin(), a2.begin() + static_cast<long>(k2), a2.end());
    float r1, r2;
    kth_smallest_pair(c.data(), n, k, k2, hist, r1, r2);
    EXPECT_EQ(r1, a[k]) << n << " " << k;
    EXPECT_EQ(r2, a2[k2]) << n << " " << k2;
  }
}

}  // namespace
}  // namespace naneye::recon::scene
