// The coarse search's window norms (window_inverse_norms, epipolar_match.hpp) against the plain
// definition window by window, and the rounding its callers use (recon/scene/round.hpp) against
// std::lround.
#include <gtest/gtest.h>

#include <climits>
#include <cmath>
#include <random>
#include <vector>

#include "../../recon/scene/round.hpp"
#include "naneye/recon/scene/epipolar_match.hpp"

namespace naneye::recon::scene {
namespace {

// 1 / sqrt(sum (I - mean)^2) over the window, or 0 where the window leaves the image, the pixel is
// not usable or the window is flat.
double plain_inverse_norm(const GrayView& im, int radius, int c, int r) {
  if (c < radius || r < radius || c + radius >= im.width || r + radius >= im.height) return 0;
  double m = 0;
  const int side = 2 * radius + 1;
  for (int dr = -radius; dr <= radius; ++dr)
    for (int dc = -radius; dc <= radius; ++dc) m += im.at(c + dc, r + dr);
  m /= side * side;
  double v = 0;
  for (int dr = -radius; dr <= radius; ++dr)
    for (int dc = -radius; dc <= radius; ++dc) v += (im.at(c + dc, r + dr) - m) * (im.at(c + dc, r + dr) - m);
  return v > 0 ? 1.0 / std::sqrt(v) : 0.0;
}

TEST(WindowNorms, EveryWindowMatchesItsPlainDefinition) {
  std::mt19937 rng(11);
  const int w = 53, h = 41, radius = 3;
  std::vector<std::uint8_t> usable(static_cast<std::size_t>(w) * h);
  for (auto& u : usable) u = rng() % 5 != 0;  // a fifth of the pixels not usable
  for (const bool integer : {true, false}) {
    // Integer DN (a mono sensor) and fractional values on a high level with little contrast (a
    // Bayer luminance: the case where sums of squares cancel most).
    std::vector<float> px(static_cast<std::size_t>(w) * h);
    std::uniform_real_distribution<float> level(0.f, 1023.f), small(600.f, 612.f);
    for (float& v : px) v = integer ? std::round(level(rng)) : small(rng);
    // A flat patch: its windows have no score.
    for (int r = 10; r < 20; ++r)
      for (int c = 20; c < 32; ++c) px[r * w + c] = 500.f;
    const GrayView im{px.data(), w, h};
    std::vector<float> out(px.size(), -1.f);
    std::vector<double> scratch(2 * static_cast<std::size_t>(w));
    window_inverse_norms(im, radius, usable.data(), out.data(), scratch.data());
    int scored = 0;
    for (int r = 0; r < h; ++r)
      for (int c = 0; c < w; ++c) {
        const double want = usable[r * w + c] ? plain_inverse_norm(im, radius, c, r) : 0.0;
        ASSERT_NEAR(out[r * w + c], want, 1e-6 * want)
            << "at " << c << ", " << r << (integer ? " DN" : " fractional");
        scored += out[r * w + c] > 0;
      }
    EXPECT_GT(scored, (w - 2 * radius) * (h - 2 * radius) / 2);
    EXPECT_EQ(out[15 * w + 26], 0.f);  // inside the flat patch
  }
}

TEST(RoundHalfAway, IsStdLroundWithinIntsRange) {
  for (const double v : {0.0, 0.5, -0.5, 1.49999999, 1.5, -1.5, 2.5, -2.5, 249.5, 0.49999999999999994, -7.25})
    EXPECT_EQ(round_half_away(v), std::lround(v)) << v;
  for (const float v : {0.5f, -0.5f, 3.5f, -3.5f, 8388607.5f, 0.49999997f})
    EXPECT_EQ(round_half_away(v), std::lround(v)) << v;
  EXPECT_EQ(round_half_away(std::nan("")), INT_MIN);
  EXPECT_EQ(round_half_away(1e300), INT_MIN);
  EXPECT_EQ(round_half_away(-1e300), INT_MIN);
}

}  // namespace
}  // namespace naneye::recon::scene
