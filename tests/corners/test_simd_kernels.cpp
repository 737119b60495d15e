// The corner fit's vector kernels (recon/corners/simd.hpp): erf and exp(-z^2) against the C
// library, the normal equations against a double-precision sum, and the 4-lane (SSE2) and 8-lane
// (AVX2, when this CPU has it) builds of the whole fit against each other on rendered corners.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "../../recon/corners/simd.hpp"
#include "corner_test_util.hpp"
#include "naneye/recon/corners/fast_fit.hpp"

namespace naneye::recon {
namespace {

using ShapeFn = void (*)(const simd::ModelParams&, const float*, const float*, int, float*, float*, float*,
                         float*, float*, float*, float*);

std::vector<ShapeFn> shape_kernels() {
  std::vector<ShapeFn> k{simd::shape_sse};
  if (simd::has_avx2_fma()) k.push_back(simd::shape_avx2);
  return k;
}

TEST(SimdKernels, ErfAndGaussianMatchTheCLibrary) {
  // u1 = yx - qx with the first edge's normal along x and k = 1: E1 = erf(yx), G1 = exp(-yx^2), for
  // yx over [-9.5, 9.5] in steps of 0.00172.
  constexpr int n = 368;
  std::vector<float> yx(n), yy(n, 0.0f), U1(n), U2(n), E1(n), E2(n), G1(n), G2(n), S(n);
  for (const ShapeFn shape : shape_kernels()) {
    double worst_erf = 0, worst_gauss = 0;
    for (int block = 0; block < 30; ++block) {
      for (int i = 0; i < n; ++i)
        yx[static_cast<std::size_t>(i)] = -9.5f + 0.00172f * static_cast<float>(block * n + i);
      shape(simd::ModelParams{0, 0, 1, 0, 0, 1, 1, 1, 0, 0, 0, 0, 0, 0}, yx.data(), yy.data(), n, U1.data(),
            U2.data(), E1.data(), E2.data(), G1.data(), G2.data(), S.data());
      for (std::size_t i = 0; i < n; ++i) {
        const double z = yx[i];
        worst_erf = std::max(worst_erf, std::abs(E1[i] - std::erf(z)));
        // Relative while exp(-z^2) is a normal float (z^2 < 87: 2^-126 = exp(-87.3)), then held
        // at the smallest normal float.
        // (Against exp of the float z^2 the kernel forms: its rounding alone is 5e-6 relative at z = 9.)
        const double z2 = static_cast<float>(yx[i] * yx[i]);
        if (z2 < 87) worst_gauss = std::max(worst_gauss, std::abs(G1[i] / std::exp(-z2) - 1.0));
        if (z * z > 87.4) {
          EXPECT_LT(G1[i], 1.3e-38f) << z;
        }
        EXPECT_EQ(E2[i], 0.0f);  // u2 = yy = 0
      }
    }
    // A&S 7.1.26 is good to 1.5e-7; evaluating 1 - t poly(t) exp(-z^2) in float adds a few ulp of
    // 1 (6e-8 each): measured 4.2e-7 (4 lanes) and 3.8e-7 (8 lanes). Expf: measured 8e-8.
    std::printf("erf worst %.2e, exp(-z^2) worst relative %.2e\n", worst_erf, worst_gauss);
    EXPECT_LT(worst_erf, 6e-7);
    EXPECT_LT(worst_gauss, 2e-7);
  }
}

// Edges 60 degrees apart (rho = 0.5): the shape is the exact blurred X-junction E[sign X1 sign X2]
// (simd.hpp), here against a double-precision quadrature of P(X1 > 0, X2 > 0) over X1, and the cross
// factors of its derivatives against the closed form erf((z2 - rho z1) / sqrt(1 - rho^2)).
TEST(SimdKernels, NonPerpendicularEdgesGiveTheExactBlurredCorner) {
  const double kPi = 3.14159265358979323846, rho = 0.5, k = 1.0 / std::sqrt(2.0);  // blur 1 px
  auto Phi = [](double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); };
  auto exact = [&](double m1, double m2) {
    double p = 0;
    const int steps = 4000;
    const double lo = -m1, hi = 9.0, h = (hi - lo) / steps;
    for (int i = 0; hi > lo && i < steps; ++i) {
      const double z = lo + (i + 0.5) * h;
      p += std::exp(-0.5 * z * z) / std::sqrt(2 * kPi) * Phi((m2 + rho * z) / std::sqrt(1 - rho * rho)) * h;
    }
    return 4 * p - 2 * Phi(m1) - 2 * Phi(m2) + 1;
  };
  constexpr int n = 64;
  std::vector<float> yx(n), yy(n), U1(n), U2(n), E1(n), E2(n), G1(n), G2(n), S(n);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> pos(-4.0f, 4.0f);
  for (int i = 0; i < n; ++i) {
    yx[static_cast<std::size_t>(i)] = pos(rng);
    yy[static_cast<std::size_t>(i)] = pos(rng);
  }
  const float c2 = 0.5f, s2 = static_cast<float>(std::sqrt(0.75));  // normal 2 at 60 degrees to normal 1
  const simd::ModelParams m{0, 0, 1, 0, c2, s2, static_cast<float>(k), 1, 0, 0, 0, 0, 0, 0};
  for (const ShapeFn shape : shape_kernels()) {
    shape(m, yx.data(), yy.data(), n, U1.data(), U2.data(), E1.data(), E2.data(), G1.data(), G2.data(),
          S.data());
    double worst_s = 0, worst_f = 0, worst_product = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double u1 = yx[i], u2 = c2 * yx[i] + s2 * yy[i];
      const double want = exact(u1, u2);  // m_k = u_k / blur
      worst_s = std::max(worst_s, std::abs(S[i] - want));
      worst_product = std::max(worst_product, std::abs(std::erf(k * u1) * std::erf(k * u2) - want));
      const double f2 = std::erf(k * (u2 - rho * u1) / std::sqrt(1 - rho * rho));
      worst_f = std::max(worst_f, std::abs(E2[i] - f2));
    }
    std::printf("rho 0.5: shape %.1e from the exact corner (the product of erfs: %.3f), cross factor %.1e\n",
                worst_s, worst_product, worst_f);
    EXPECT_LT(worst_s, 2e-4);        // 8-node Gauss-Legendre in float
    EXPECT_GT(worst_product, 0.05);  // what the product of erfs would miss
    EXPECT_LT(worst_f, 1e-6);
  }
}

TEST(SimdKernels, NormalEquationsMatchADoubleSum) {
  constexpr int K = 9, n = 203, nv = 208;  // n not a multiple of the vector length: tails zeroed
  std::mt19937 rng(5);
  std::normal_distribution<float> g(0.0f, 1.0f);
  std::vector<std::vector<float>> J(K + 1, std::vector<float>(nv, 0.0f)), Jw(K, std::vector<float>(nv, 0.0f));
  for (int c = 0; c <= K; ++c)
    for (int i = 0; i < n; ++i) J[static_cast<std::size_t>(c)][static_cast<std::size_t>(i)] = g(rng);
  for (int c = 0; c < K; ++c)
    for (int i = 0; i < n; ++i)
      Jw[static_cast<std::size_t>(c)][static_cast<std::size_t>(i)] =
          0.5f * J[static_cast<std::size_t>(c)][static_cast<std::size_t>(i)];
  std::array<const float*, K + 1> cols;
  std::array<const float*, K> jw;
  for (std::size_t c = 0; c <= K; ++c) cols[c] = J[c].data();
  for (std::size_t c = 0; c < K; ++c) jw[c] = Jw[c].data();
  std::array<double, (K + 1) * K> sse{}, avx{};
  simd::normal_equations_sse<K>(cols, jw, nv, sse);
  if (simd::has_avx2_fma()) simd::normal_equations_avx2<K>(cols, jw, nv, avx);
  for (int a = 0; a < K; ++a) {
    for (int b = a; b <= K; ++b) {
      double ref = 0;
      for (std::size_t i = 0; i < n; ++i)
        ref += 0.5 * J[static_cast<std::size_t>(a)][i] * J[static_cast<std::size_t>(b)][i];
      const auto k = static_cast<std::size_t>(a * (K + 1) + b);
      EXPECT_NEAR(sse[k], ref, 2e-5 * (1 + std::abs(ref))) << a << "," << b;
      if (simd::has_avx2_fma()) {
        EXPECT_NEAR(avx[k], ref, 2e-5 * (1 + std::abs(ref))) << a << "," << b;
      }
    }
  }
}

TEST(SimdKernels, FourAndEightLaneFitsAgree) {
  if (!simd::has_avx2_fma()) GTEST_SKIP() << "no AVX2 + FMA on this CPU: only the 4-lane build runs";
  const StereoRig& rig = test::paper_d3();
  CornerDetector det(rig.left);
  std::mt19937_64 rng(33);
  const sim::RenderedPair p = test::render(false, test::random_pose(rng, 65, 75, 20, 2), 77);
  CornerResult found;
  ASSERT_TRUE(det.detect_full(sim::raw_view(p.left, false), found));
  const UndistortMap map(rig.left);
  const LumaView v{det.luminance().data(), 250, 250, 1, 249, 249};
  FastFitScratch sse, avx;
  sse.use_avx2 = false;
  avx.use_avx2 = true;
  double worst = 0;
  for (int i = 0; i < found.count; ++i) {
    const Corner& c = found.corners[static_cast<std::size_t>(i)];
    SaddleInit init{c.px + Eigen::Vector2d(0.3, -0.2), c.theta_row, c.theta_col, 0.9};
    SaddleFit a, b;
    ASSERT_TRUE(fit_saddle_fast(v, rig.left, map, init, nullptr, 6.0, 50, 1e-4, sse, a));
    ASSERT_TRUE(fit_saddle_fast(v, rig.left, map, init, nullptr, 6.0, 50, 1e-4, avx, b));
    worst = std::max(worst, (a.px - b.px).norm());
    EXPECT_NEAR(a.sigma, b.sigma, 1e-3);
    EXPECT_NEAR(a.rms, b.rms, 1e-2 * (1 + a.rms));
  }
  // Float sums in another order: the two builds agree far below the corner noise (~0.01 px).
  EXPECT_LT(worst, 1e-4);
  std::printf("4- vs 8-lane fits: worst corner difference %.2e px over %d corners\n", worst, found.count);
}

}  // namespace
}  // namespace naneye::recon
