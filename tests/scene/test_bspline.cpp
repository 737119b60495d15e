// The cubic B-spline coefficients (recon/include/naneye/recon/scene/bspline.hpp) and their sampling
// (recon/scene/interpolate.hpp): they interpolate the image, ignore the padding outside the active
// rectangle, reproduce what the mirror boundary implies, and between the samples of a band-limited
// texture err far less than Keys' cubic on the same samples (the anchor, printed beside).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

#include "../../recon/scene/interpolate.hpp"
#include "naneye/recon/scene/bspline.hpp"

namespace naneye::recon::scene {
namespace bspline_test {

constexpr int kW = 60, kH = 50;
// NanEye's layout: the last column is padding, the first and last rows reference pixels.
constexpr ActiveRect kActive{kW - 1, 1, kH - 1};

std::vector<float> random_image(std::mt19937& rng) {
  std::uniform_real_distribution<float> level(0.f, 1023.f);
  std::vector<float> im(static_cast<std::size_t>(kW * kH));
  for (float& v : im) v = level(rng);
  return im;
}

std::vector<float> coefficients(const std::vector<float>& im) {
  std::vector<float> c(im.size(), -1.f), scratch(im.size());
  bspline_coefficients(GrayView{im.data(), kW, kH}, kActive, c.data(), scratch.data());
  return c;
}

TEST(BSpline, InterpolatesEveryActivePixel) {
  std::mt19937 rng(7);
  const std::vector<float> im = random_image(rng), c = coefficients(im);
  const GrayView cv{c.data(), kW, kH};
  double worst = 0;
  // Every active pixel whose 16 taps exist, the edges' too (their taps read the mirrored
  // coefficients beyond the rectangle).
  for (int r = 1; r < kH - 3; ++r)
    for (int col = 1; col < kW - 3; ++col)
      worst = std::max(worst, double(std::abs(sample_bspline(cv, float(col), float(r)) - im[r * kW + col])));
  std::printf("largest |spline - sample| at the pixels: %.2e DN of 1023\n", worst);
  // Float rounding of a contracting filter over values up to 1023 (2^-14 relative ~ 0.06 DN would be a
  // bug; measured 2026-12-06: ~1e-4).
  EXPECT_LT(worst, 2e-3);
}

TEST(BSpline, PaddingNeverReachesTheCoefficients) {
  std::mt19937 rng(9);
  std::vector<float> im = random_image(rng);
  const std::vector<float> before = coefficients(im);
  for (int r = 0; r < kH; ++r) im[r * kW + kW - 1] = 1e6f;                       // the padding column
  for (int col = 0; col < kW; ++col) im[col] = im[(kH - 1) * kW + col] = -1e6f;  // the reference rows
  EXPECT_EQ(before, coefficients(im));
}

TEST(BSpline, ConstantAndMirroredContinuation) {
  // A constant image's coefficients are that constant everywhere, the padding's places included.
  std::vector<float> flat(static_cast<std::size_t>(kW * kH), 300.f);
  for (float c : coefficients(flat)) EXPECT_NEAR(c, 300.f, 1e-3);
  // Beyond the rectangle the coefficients mirror those inside (column kW - 1 is column kW - 3, row 0
  // is row 2 and row kH - 1 row kH - 3, about the last and first active ones).
  std::mt19937 rng(11);
  const std::vector<float> c = coefficients(random_image(rng));
  for (int r = 0; r < kH; ++r) EXPECT_EQ(c[r * kW + kW - 1], c[r * kW + kW - 3]) << r;
  for (int col = 0; col < kW; ++col) {
    EXPECT_EQ(c[col], c[2 * kW + col]) << col;
    EXPECT_EQ(c[(kH - 1) * kW + col], c[(kH - 3) * kW + col]) << col;
  }
}

// One line (the dense step's rows): the coefficients reproduce every sample through the B-spline's
// taps (c[k-1] + 4 c[k] + c[k+1]) / 6, the ends through the mirrored coefficients, for any length
// from 2 (shorter than the causal start's 16 terms: the mirror folds many times); in place gives the
// same bits.
TEST(BSpline, LineInterpolatesEverySampleAtAnyLengthAndInPlace) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> level(0.f, 1023.f);
  for (int n : {2, 3, 5, 16, 17, 40}) {
    std::vector<float> s(static_cast<std::size_t>(n)), c(s.size());
    for (float& v : s) v = level(rng);
    bspline_coefficients_line(s.data(), n, c.data());
    std::vector<float> in_place = s;
    bspline_coefficients_line(in_place.data(), n, in_place.data());
    EXPECT_EQ(c, in_place) << n;
    const auto at = [&](int k) {
      return double(c[static_cast<std::size_t>(k < 0 ? -k : k >= n ? 2 * n - 2 - k : k)]);
    };
    double worst = 0;
    for (int k = 0; k < n; ++k)
      worst = std::max(worst, std::abs((at(k - 1) + 4 * at(k) + at(k + 1)) / 6 - s[k]));
    EXPECT_LT(worst, 2e-3) << n;
  }
  float one_sample[1] = {5.f};
  EXPECT_THROW(bspline_coefficients_line(one_sample, 1, one_sample), std::invalid_argument);
}

TEST(BSpline, RefusesARectangleTooSmallForItsStart) {
  std::vector<float> im(static_cast<std::size_t>(kW * kH), 1.f), c(im.size()), scratch(im.size());
  // The causal start sums 16 terms of the rectangle's own rows and columns.
  EXPECT_THROW(
      bspline_coefficients(GrayView{im.data(), kW, kH}, ActiveRect{16, 0, 40}, c.data(), scratch.data()),
      std::invalid_argument);
  EXPECT_THROW(
      bspline_coefficients(GrayView{im.data(), kW, kH}, ActiveRect{40, 2, 18}, c.data(), scratch.data()),
      std::invalid_argument);
  EXPECT_THROW(
      bspline_coefficients(GrayView{im.data(), kW, kH}, ActiveRect{kW + 1, 0, kH}, c.data(), scratch.data()),
      std::invalid_argument);
  EXPECT_NO_THROW(
      bspline_coefficients(GrayView{im.data(), kW, kH}, ActiveRect{17, 0, 17}, c.data(), scratch.data()));
}

// Between the samples of plane waves (wavelengths 4-10 px, the texture's band on this camera) the
// spline's largest error, against Keys' cubic on the same pixels (both in the image's interior,
// 12 px from the edges, where the mirror boundary's effect, |sqrt(3) - 2|^12 ~ 1e-7, is gone).
TEST(BSpline, ErrsFarLessThanKeysBetweenSamples) {
  for (double wavelength : {4.0, 6.0, 10.0}) {
    std::mt19937 rng(static_cast<unsigned>(wavelength * 10));
    std::uniform_real_distribution<double> angle(0, M_PI), phase(0, 2 * M_PI), frac(0, 1);
    double worst_spline = 0, worst_keys = 0;
    for (int wave = 0; wave < 20; ++wave) {
      const double a = angle(rng), k = 2 * M_PI / wavelength, ph = phase(rng);
      const auto truth = [&](double x, double y) {
        return 500 + 100 * std::sin(k * (std::cos(a) * x + std::sin(a) * y) + ph);
      };
      std::vector<float> im(static_cast<std::size_t>(kW * kH));
      for (int r = 0; r < kH; ++r)
        for (int col = 0; col < kW; ++col) im[r * kW + col] = static_cast<float>(truth(col, r));
      const std::vector<float> c = coefficients(im);
      const GrayView iv{im.data(), kW, kH}, cv{c.data(), kW, kH};
      for (int t = 0; t < 200; ++t) {
        const float x = static_cast<float>(12 + (kW - 27) * frac(rng)),
                    y = static_cast<float>(12 + (kH - 27) * frac(rng));
        worst_spline = std::max(worst_spline, std::abs(sample_bspline(cv, x, y) - truth(x, y)));
        worst_keys = std::max(worst_keys, std::abs(sample_cubic(iv, x, y) - truth(x, y)));
      }
    }
    std::printf("wavelength %4.1f px, amplitude 100 DN: largest error  B-spline %6.3f DN  Keys %6.3f DN\n",
                wavelength, worst_spline, worst_keys);
    // Measured 2026-12-06 (the theory: the cardinal spline's error at 4 px ~ 1/5 of Keys' and falls
    // as the fourth power of the frequency, Keys' as the third).
    EXPECT_LT(worst_spline, 0.35 * worst_keys) << wavelength;
  }
}

// The knot derivative as a filter on the samples (the dense fit's gradient): the same as the
// coefficients' central difference on a line, the plane wave's own slope where the spline follows
// it, and the white-noise gain the fit's sigma uses (dense_subpixel.cpp).
TEST(BSpline, KnotDerivativeFilterIsTheInterpolantsSlope) {
  constexpr int n = 96;
  std::vector<float> line(n), c(n);
  for (const double period : {4.0, 6.0, 10.0}) {
    const double om = 2 * std::numbers::pi / period;
    for (int x = 0; x < n; ++x) line[x] = static_cast<float>(100 * std::sin(om * x + 0.3));
    bspline_coefficients_line(line.data(), n, c.data());
    for (int x = 30; x < 66; ++x) {
      double g = 0;
      for (int k = -kKnotDerivativeReach; k <= kKnotDerivativeReach; ++k)
        g += bspline_knot_derivative_tap(k) * line[x + k];
      EXPECT_NEAR(g, 0.5 * (c[x + 1] - c[x - 1]), 1e-3) << period << " " << x;
      // The cubic spline's slope error on a 4 px wave is ~5 % of its amplitude, ~0.1 % at 10 px.
      EXPECT_NEAR(g, 100 * om * std::cos(om * x + 0.3), (period < 5 ? 0.06 : 0.01) * 100 * om)
          << period << " " << x;
    }
  }
  double gain = 0, odd = 0;
  for (int k = -kKnotDerivativeReach; k <= kKnotDerivativeReach; ++k) {
    gain += bspline_knot_derivative_tap(k) * bspline_knot_derivative_tap(k);
    odd += std::abs(bspline_knot_derivative_tap(k) + bspline_knot_derivative_tap(-k));
  }
  EXPECT_NEAR(gain, 1.3923, 1e-4);
  EXPECT_EQ(odd, 0.0);
  EXPECT_EQ(bspline_knot_derivative_tap(kKnotDerivativeReach + 1), 0.0);
}

// What the interpolant does to white noise (bspline_noise_autocorrelation): white noise on a line,
// through the prefilter and sampled at a fractional offset f over the whole line, has the variance
// R_f(0) and the lag correlations R_f(1), R_f(2); the table against that Monte Carlo, and its exact
// points: 1 at f = 0 (the samples themselves), 0.756 at 1/2, symmetric in f -> 1 - f.
TEST(BSpline, NoiseAutocorrelationIsWhatInterpolatingWhiteNoiseGives) {
  constexpr int n = 4096, lines = 64;
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0, 1);
  std::vector<float> line(n), c(n);
  for (const double f : {0.0, 0.25, 0.5, 0.8}) {
    double r[3] = {};
    long count = 0;
    for (int l = 0; l < lines; ++l) {
      for (float& x : line) x = static_cast<float>(g(rng));
      bspline_coefficients_line(line.data(), n, c.data());
      float w[4];
      bspline_weights(static_cast<float>(f), w);
      std::vector<double> v(n, 0.0);
      for (int x = 8; x < n - 8; ++x)
        for (int k = 0; k < 4; ++k) v[x] += w[k] * c[x - 1 + k];
      for (int x = 16; x < n - 16; ++x, ++count)
        for (int lag = 0; lag < 3; ++lag) r[lag] += v[x] * v[x + lag];
    }
    for (int lag = 0; lag < 3; ++lag) {
      r[lag] /= static_cast<double>(count);
      // ~260 k products: their mean's spread is ~0.003 (lag 0) at these variances.
      EXPECT_NEAR(bspline_noise_autocorrelation(f, lag), r[lag], 0.01) << f << " " << lag;
    }
    std::printf("f %.2f  R(0) %.4f (Monte Carlo %.4f)  R(1) %.4f (%.4f)  R(2) %.4f (%.4f)\n", f,
                bspline_noise_autocorrelation(f, 0), r[0], bspline_noise_autocorrelation(f, 1), r[1],
                bspline_noise_autocorrelation(f, 2), r[2]);
  }
  EXPECT_DOUBLE_EQ(bspline_noise_autocorrelation(0.0, 0), 1.0);
  EXPECT_NEAR(bspline_noise_autocorrelation(0.0, 1), 0.0, 1e-12);
  EXPECT_NEAR(bspline_noise_autocorrelation(0.5, 0), 0.7561, 1e-4);
  EXPECT_NEAR(bspline_noise_autocorrelation(0.3, 0), bspline_noise_autocorrelation(0.7, 0), 1e-9);
  EXPECT_THROW(bspline_noise_autocorrelation(0.5, kNoiseLagReach + 1), std::invalid_argument);
}

// The LK's all-lags look-up (lk_affine.cpp) gives each lag's value bit for bit, at the table's
// entries, between them and at the clamped ends.
TEST(BSpline, NoiseAutocorrelationsForAllLagsAreTheSingleLookUps) {
  for (const double f : {-0.1, 0.0, 1.0 / 256, 0.123456, 0.5, 0.77, 255.5 / 256, 1.0, 1.3}) {
    double all[kNoiseLagReach + 1];
    bspline_noise_autocorrelations(f, all);
    for (int lag = 0; lag <= kNoiseLagReach; ++lag) {
      EXPECT_EQ(all[lag], bspline_noise_autocorrelation(f, lag)) << f << " " << lag;
      EXPECT_EQ(all[lag], bspline_noise_autocorrelation(f, -lag)) << f << " " << lag;
    }
  }
}

}  // namespace bspline_test
}  // namespace naneye::recon::scene
