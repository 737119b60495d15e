// The frame's noise model (corners/noise.hpp): var = a DN + b from one frame, board included.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "naneye/recon/corners/noise.hpp"

namespace naneye::recon {
namespace {

// A checkerboard (squares of `square` px, levels lo / hi, a soft 1 px ramp at the edges) under a
// horizontal shading gradient, with Gaussian noise of variance a * level + b.
std::vector<float> noisy_board(int w, int h, int square, double lo, double hi, double a, double b,
                               unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::vector<float> img(static_cast<std::size_t>(w) * h);
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const bool white = ((r / square) + (c / square)) % 2 == 0;
      const double shade = 0.6 + 0.4 * c / w;
      const double level = shade * (white ? hi : lo);
      img[static_cast<std::size_t>(r * w + c)] =
          static_cast<float>(level + std::sqrt(a * level + b) * n01(rng));
    }
  }
  return img;
}

TEST(Noise, ShotAndReadNoiseRecoveredFromOneBoardFrame) {
  NoiseEstimator est;
  for (const auto& [a, b] : std::vector<std::pair<double, double>>{{0.14, 6.0}, {0.08, 3.2}, {0.5, 10.0}}) {
    const auto img = noisy_board(250, 250, 7, 60, 700, a, b, 3);
    const NoiseModel m = est.estimate(img.data(), 250, 0, 250, 250, 1);
    std::printf("truth a %.3f b %.2f: estimated a %.3f b %.2f from %d levels; sigma at 400 DN %.2f vs %.2f\n",
                a, b, m.a, m.b, m.levels, std::sqrt(m.variance(400)), std::sqrt(a * 400 + b));
    // What the decisions use: the variance over the board's levels, within 15 % (a bin of >= 48
    // blocks has a ~18 % standard error; the fit pools ~20 of them).
    for (const double level : {60.0, 200.0, 400.0, 700.0}) {
      EXPECT_NEAR(m.variance(level), a * level + b, 0.15 * (a * level + b)) << level;
    }
  }
}

TEST(Noise, SameSiteBlocksOfAMosaic) {
  // Step 2 (Bayer): the four sites each form their own blocks; a site-to-site offset (unequal
  // channel gains left in) must not count as noise.
  const auto img0 = noisy_board(250, 250, 8, 80, 600, 0.14, 6.0, 4);
  std::vector<float> img = img0;
  for (int r = 0; r < 250; ++r)
    for (int c = 0; c < 250; ++c)
      img[static_cast<std::size_t>(r * 250 + c)] += ((r & 1) * 2 + (c & 1)) * 25.0f;
  NoiseEstimator est;
  const NoiseModel m = est.estimate(img.data(), 250, 0, 250, 250, 2);
  // A bin at level L holds blocks of each site, whose light is L less the site's offset (37.5 DN
  // on average): their noise is that of the light.
  for (const double level : {100.0, 400.0}) {
    const double truth = 0.14 * (level - 37.5) + 6.0;
    EXPECT_NEAR(m.variance(level), truth, 0.15 * truth) << level;
  }
}

TEST(Noise, NoiseFreeImageGivesTheQuantisationFloor) {
  std::vector<float> img(250 * 250);
  for (int r = 0; r < 250; ++r)
    for (int c = 0; c < 250; ++c) img[static_cast<std::size_t>(r * 250 + c)] = std::round(100.0f + 2.0f * c);
  NoiseEstimator est;
  const NoiseModel m = est.estimate(img.data(), 250, 0, 250, 250, 1);
  EXPECT_NEAR(m.variance(300), 1.0 / 12.0, 0.05);
}

TEST(Noise, UpperNormalQuantile) {
  EXPECT_NEAR(upper_normal_quantile(1e-3), 3.0902, 1e-3);
  EXPECT_NEAR(upper_normal_quantile(0.5), 0.0, 1e-6);
}

}  // namespace
}  // namespace naneye::recon
