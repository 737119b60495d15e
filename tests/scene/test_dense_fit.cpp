// The sub-pixel step's per-pixel fits as row kernels (recon/scene/dense_fit.cpp, dense_simd.hpp):
// the scalar (SSE2) and AVX2 (when this CPU has it) builds give the plain loops' bits, NaNs included,
// and leave what the plain loops leave untouched as it was.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "../../recon/corners/simd.hpp"
#include "../../recon/scene/dense_simd.hpp"

namespace naneye::recon::scene {
namespace {

std::vector<bool> fit_kernel_builds() {
  std::vector<bool> b{false};
  if (simd::has_avx2()) b.push_back(true);
  return b;
}

// Bits of a float, NaN's included.
std::uint32_t bits_of(float v) {
  std::uint32_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

// The last iteration's fit (RectifiedMatcher::refine) against its plain double loop: every refusal
// (no disparity, an infinite one, no data, N < 4, det <= 0), a <= 0, clamped and free steps, odd
// spans (the vector tail), and the outputs a refused pixel leaves as they were.
TEST(DenseKernels, FitRowGivesThePlainLoopsBits) {
  std::mt19937 rng(21);
  constexpr int w = 45;
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  for (int trial = 0; trial < 40; ++trial) {
    std::vector<float> S(10 * w), m(w), d(w);
    for (int x = 0; x < w; ++x) {
      const float N = static_cast<float>(rng() % 50), mw = 40 * u(rng), mg = 30 * u(rng), ml = 40 * u(rng);
      const float ww = 500 + 400 * u(rng), gg = 500 + 400 * u(rng), wg = 700 * u(rng);
      const float v[10] = {N,
                           N * mw,
                           N * ml,
                           N * mg,
                           ww + N * mw * mw,
                           gg + N * mg * mg,
                           wg + N * mw * mg,
                           300 * u(rng) + N * mw * ml,
                           300 * u(rng) + N * mg * ml,
                           400 + 300 * u(rng) + N * ml * ml};
      for (int k = 0; k < 10; ++k) S[k * w + x] = v[k];
      m[x] = x % 9 == 4 ? 0.f : 1.f;
      d[x] = x % 11 == 3 ? NAN : x % 13 == 6 ? INFINITY : 20 * u(rng);
    }
    const int lo = static_cast<int>(rng() % 10), hi = lo + static_cast<int>(rng() % (w - lo + 1));
    // The plain loop (refine's before 2026-12-05) on its own copies; -7: untouched.
    std::vector<float> want(12 * w, -7.f), wd = d;
    for (int x = lo; x < hi; ++x) {
      float* o = &want[x];  // n, step, solved, a, b, c, s2, z, sww, swg, sgg at o[k * w]
      const float N = S[x];
      o[0] = N;
      o[w] = o[2 * w] = 0;
      if (!std::isfinite(wd[x]) || m[x] == 0 || N < 4) {
        wd[x] = NAN;
        continue;
      }
      const double inv = 1.0 / N, sw = S[w + x], sl = S[2 * w + x], sgr = S[3 * w + x];
      const double Sww = S[4 * w + x] - sw * sw * inv, Sgg = S[5 * w + x] - sgr * sgr * inv;
      const double Swg = S[6 * w + x] - sw * sgr * inv, Swl = S[7 * w + x] - sw * sl * inv;
      const double Sgl = S[8 * w + x] - sgr * sl * inv, det = Sww * Sgg - Swg * Swg;
      if (!(det > 0)) {
        wd[x] = NAN;
        continue;
      }
      const double a = (Sgg * Swl - Swg * Sgl) / det, c = (Swg * Swl - Sww * Sgl) / det;
      const double Sll = S[9 * w + x] - sl * sl * inv;
      const double v[8] = {a,         (sl - a * sw + c * sgr) * inv,
                           c,         std::max(0.0, Sll - a * Swl + c * Sgl) / std::max(1.0, N - 3.0),
                           Sww / det, Sww,
                           Swg,       Sgg};
      for (int k = 0; k < 8; ++k) o[(3 + k) * w] = static_cast<float>(v[k]);
      if (!(a > 0)) continue;
      o[w] = static_cast<float>(std::clamp(c, -0.5, 0.5));
      o[2 * w] = 1;
    }
    for (const bool avx2 : fit_kernel_builds()) {
      std::vector<float> got(12 * w, -7.f), gd = d;
      dense_simd::FitRow r{};
      for (int k = 0; k < 10; ++k) r.s[k] = S.data() + k * w;
      r.m = m.data();
      r.d = gd.data();
      float** out[11] = {&r.n, &r.step, &r.solved, &r.a, &r.b, &r.c, &r.s2, &r.z, &r.sww, &r.swg, &r.sgg};
      for (int k = 0; k < 11; ++k) *out[k] = got.data() + k * w;
      r.lo = lo;
      r.hi = hi;
      dense_simd::fit_row(avx2, r);
      for (int x = 0; x < w; ++x) {
        ASSERT_EQ(bits_of(gd[x]), bits_of(wd[x])) << (avx2 ? "avx2 d " : "sse d ") << x;
        for (int k = 0; k < 11; ++k)
          ASSERT_EQ(bits_of(got[k * w + x]), bits_of(want[k * w + x]))
              << (avx2 ? "avx2 " : "sse ") << k << " " << x;
      }
    }
  }
}

// The earlier iterations' window mean against its plain loop: no disparity (untouched), an empty
// window (d kept), odd spans.
TEST(DenseKernels, MeanRowGivesThePlainLoopsBits) {
  std::mt19937 rng(22);
  constexpr int w = 53;
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<float> sum(w), cnt(w), d(w);
    for (int x = 0; x < w; ++x) {
      cnt[x] = x % 7 == 2 ? 0.f : static_cast<float>(rng() % 49);
      sum[x] = cnt[x] * (30 + u(rng));
      d[x] = x % 11 == 3 ? NAN : x % 13 == 6 ? -INFINITY : 30 + u(rng);
    }
    const int lo = static_cast<int>(rng() % 10), hi = lo + static_cast<int>(rng() % (w - lo + 1));
    std::vector<float> wd = d, wm(w, -7.f);
    for (int x = lo; x < hi; ++x) {
      if (!std::isfinite(wd[x])) continue;
      const float next = cnt[x] > 0 ? sum[x] / cnt[x] : wd[x];
      wm[x] = next - wd[x];
      wd[x] = next;
    }
    for (const bool avx2 : fit_kernel_builds()) {
      std::vector<float> gd = d, gm(w, -7.f);
      dense_simd::mean_row(avx2, sum.data(), cnt.data(), gd.data(), gm.data(), lo, hi);
      for (int x = 0; x < w; ++x) {
        ASSERT_EQ(bits_of(gd[x]), bits_of(wd[x])) << (avx2 ? "avx2 " : "sse ") << x;
        ASSERT_EQ(bits_of(gm[x]), bits_of(wm[x])) << (avx2 ? "avx2 " : "sse ") << x;
      }
    }
  }
}

// window_detail()'s solve against its plain double loop: N < 4, det <= 0, odd spans.
TEST(DenseKernels, DetailRowGivesThePlainLoopsBits) {
  std::mt19937 rng(23);
  constexpr int w = 45;
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  for (int trial = 0; trial < 40; ++trial) {
    std::vector<float> S(9 * w), sgq(w);
    for (int x = 0; x < w; ++x) {
      const float N = static_cast<float>(rng() % 50), mw = 40 * u(rng), mg = 30 * u(rng);
      const float v[9] = {N,
                          N * mw,
                          0,
                          N * mg,
                          500 + 400 * u(rng) + N * mw * mw,
                          500 + 400 * u(rng) + N * mg * mg,
                          700 * u(rng) + N * mw * mg,
                          80 * u(rng),
                          60 * u(rng)};
      for (int k = 0; k < 9; ++k) S[k * w + x] = v[k];
      sgq[x] = 5 * u(rng);
    }
    const int lo = static_cast<int>(rng() % 10), hi = lo + static_cast<int>(rng() % (w - lo + 1));
    std::vector<float> want(w, -7.f);
    for (int x = lo; x < hi; ++x) {
      const double N = S[x];
      if (!(N >= 4)) {
        want[x] = 0.f;
        continue;
      }
      const double inv = 1.0 / N, sw = S[w + x], sg = S[3 * w + x];
      const double Sww = S[4 * w + x] - sw * sw * inv, Sgg = S[5 * w + x] - sg * sg * inv;
      const double Swg = S[6 * w + x] - sw * sg * inv, det = Sww * Sgg - Swg * Swg;
      const double wgq_c = S[7 * w + x] - sw * inv * sgq[x], ggq_c = S[8 * w + x] - sg * inv * sgq[x];
      want[x] = det > 0 ? static_cast<float>((Sww * ggq_c - Swg * wgq_c) / det) : 0.f;
    }
    for (const bool avx2 : fit_kernel_builds()) {
      std::vector<float> got(w, -7.f);
      dense_simd::DetailRow r{};
      for (int k = 0; k < 9; ++k) r.s[k] = S.data() + k * w;
      r.sgq = sgq.data();
      r.out = got.data();
      r.lo = lo;
      r.hi = hi;
      dense_simd::detail_row(avx2, r);
      for (int x = 0; x < w; ++x)
        ASSERT_EQ(bits_of(got[x]), bits_of(want[x])) << (avx2 ? "avx2 " : "sse ") << x;
    }
  }
}

// The last iteration's update against its plain loop: unsolved (NaN), smooth and not, odd spans.
TEST(DenseKernels, UpdateRowGivesThePlainLoopsBits) {
  std::mt19937 rng(24);
  constexpr int w = 53;
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<float> solved(w), step(w), q(w), q_win(w), s2(w), z(w), d(w);
    for (int x = 0; x < w; ++x) {
      solved[x] = x % 5 == 1 ? 0.f : 1.f;
      step[x] = 0.5f * u(rng);
      q[x] = 0.3f * u(rng);
      q_win[x] = 0.3f * u(rng);
      s2[x] = 4 + 3 * u(rng);
      z[x] = 0.004f * (1.2f + u(rng));
      d[x] = 30 + u(rng);
    }
    const int lo = static_cast<int>(rng() % 10), hi = lo + static_cast<int>(rng() % (w - lo + 1));
    std::vector<float> wd = d;
    int smooth_seen = 0;
    for (int x = lo; x < hi; ++x) {
      if (!(solved[x] > 0)) {
        wd[x] = NAN;
        continue;
      }
      const float move = q_win[x] - q[x], noise = 3.f * std::sqrt(s2[x] * z[x]);
      const bool smooth = std::abs(q[x]) <= noise && std::abs(move) <= noise;
      smooth_seen += smooth;
      wd[x] += step[x] + (smooth ? move : 0.f);
    }
    if (hi - lo > 20) {
      EXPECT_GT(smooth_seen, 0);  // both gate outcomes occur
    }
    for (const bool avx2 : fit_kernel_builds()) {
      std::vector<float> gd = d;
      const dense_simd::UpdateRow r{solved.data(), step.data(), q.data(), q_win.data(), s2.data(), z.data(),
                                    gd.data(),     lo,          hi};
      dense_simd::update_row(avx2, r);
      for (int x = 0; x < w; ++x) ASSERT_EQ(bits_of(gd[x]), bits_of(wd[x])) << (avx2 ? "avx2 " : "sse ") << x;
    }
  }
}

// correlation()'s steps against their plain loops: the residual's gate (no data, no disparity, s2
// at and around the double limit, which no float equals), the centring and kappa, odd spans.
TEST(DenseKernels, CorrelationRowsGiveThePlainLoopsBits) {
  std::mt19937 rng(25);
  constexpr int w = 61;
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  const double lim = 3 * 1.2345678901234;  // between two floats
  const float near = static_cast<float>(lim);
  const float below = near > lim ? std::nextafter(near, 0.f) : near, above = std::nextafter(below, 10.f);
  ASSERT_TRUE(below < lim && above > lim);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<float> p[9];
    for (auto& v : p) v.resize(w);
    for (int x = 0; x < w; ++x) {
      for (int k = 0; k < 9; ++k) p[k][x] = 20 * u(rng);
      p[0][x] = x % 7 == 1 ? 0.f : x % 7 == 2 ? 3.f : 1.f;                 // m; N for the centring
      p[4][x] = x % 11 == 3 ? NAN : x % 13 == 5 ? INFINITY : p[4][x];      // d
      p[5][x] = x % 3 == 0 ? below : x % 3 == 1 ? above : 4 + 3 * u(rng);  // s2
      if (x % 5 == 4) p[6][x] = 0.f;                                       // szz (kappa)
    }
    const int lo = static_cast<int>(rng() % 10), hi = lo + static_cast<int>(rng() % (w - lo + 1));
    std::vector<float> we(w, -7.f), wz(w, -7.f), wzz(w, -7.f), wzh(w, -7.f), wk(w, -7.f);
    for (int x = lo; x < hi; ++x) {
      const bool use = p[0][x] > 0 && std::isfinite(p[4][x]) && p[5][x] <= lim;
      we[x] = use ? p[6][x] * p[1][x] + p[7][x] - p[8][x] * p[3][x] - p[2][x] : 0.f;
      wz[x] = p[0][x] > 0 ? p[3][x] - p[7][x] / std::max(1.f, p[0][x]) : 0.f;
      wzz[x] = wz[x] * wz[x];
      wzh[x] = 0;
      wk[x] = p[6][x] > 0 ? std::max(0.f, p[1][x] / p[6][x]) : 1.f;
    }
    for (const bool avx2 : fit_kernel_builds()) {
      std::vector<float> e(w, -7.f), z(w, -7.f), zz(w, -7.f), zh(w, -7.f), k(w, -7.f);
      const dense_simd::ResidualRow r{p[0].data(), p[1].data(), p[2].data(), p[3].data(), p[4].data(),
                                      p[5].data(), p[6].data(), p[7].data(), p[8].data(), e.data()};
      dense_simd::residual_row(avx2, r, lim, static_cast<std::size_t>(lo), static_cast<std::size_t>(hi));
      dense_simd::centre_row(avx2, p[0].data(), p[3].data(), p[7].data(), p[0].data(), z.data(), zz.data(),
                             zh.data(), lo, hi);
      dense_simd::kappa_row(avx2, p[6].data(), p[1].data(), k.data(), lo, hi);
      for (int x = 0; x < w; ++x) {
        const char* b = avx2 ? "avx2 " : "sse ";
        ASSERT_EQ(bits_of(e[x]), bits_of(we[x])) << b << "e " << x;
        ASSERT_EQ(bits_of(z[x]), bits_of(wz[x])) << b << "z " << x;
        ASSERT_EQ(bits_of(zz[x]), bits_of(wzz[x])) << b << "zz " << x;
        ASSERT_EQ(bits_of(zh[x]), bits_of(wzh[x])) << b << "zh " << x;
        ASSERT_EQ(bits_of(k[x]), bits_of(wk[x])) << b << "kappa " << x;
      }
    }
  }
}

}  // namespace
}  // namespace naneye::recon::scene
