// The affine LK's sampling kernel (recon/scene/lk_sample.hpp): every width gives the plain loop's
// bits, refuses the same windows, and a degenerate warp is refused rather than read out of bounds.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "../../recon/corners/simd.hpp"
#include "../../recon/scene/interpolate.hpp"
#include "../../recon/scene/lk_sample.hpp"

namespace naneye::recon::scene {
namespace {

struct Image {
  std::vector<float> px;
  GrayView view;
};

Image noise_image(int w, int h, std::mt19937& rng) {
  Image im;
  std::uniform_real_distribution<float> level(0.f, 1023.f);
  im.px.resize(static_cast<std::size_t>(w) * h);
  for (float& v : im.px) v = level(rng);
  im.view = GrayView{im.px.data(), w, h};
  return im;
}

std::vector<int> widths() {
  std::vector<int> l{1, 4};
  if (simd::has_avx2()) l.push_back(8);
  return l;
}

TEST(LkSample, EveryWidthGivesThePlainLoopsBits) {
  std::mt19937 rng(3);
  const Image im = noise_image(61, 47, rng);
  std::uniform_real_distribution<float> jitter(-0.3f, 0.3f), shift(20.f, 26.f);
  int compared = 0;
  for (int side : {3, 7, 9, 11}) {  // 9, 49, 81, 121 points: every tail length of 8 lanes
    const int n = side * side;
    std::vector<float> qx(n), qy(n);
    for (int k = 0; k < n; ++k) {
      qx[k] = static_cast<float>(k % side - side / 2) + 0.1f * jitter(rng);
      qy[k] = static_cast<float>(k / side - side / 2) + 0.1f * jitter(rng);
    }
    for (int trial = 0; trial < 50; ++trial) {
      lk_sample::Warp w{{1 + jitter(rng), jitter(rng), shift(rng), jitter(rng), 1 + jitter(rng), shift(rng)}};
      std::vector<float> ref(n), got(n);
      ASSERT_TRUE(lk_sample::sample_window_lanes(1, im.view, w, qx.data(), qy.data(), n, ref.data()));
      // The plain loop is the cubic B-spline at the float positions (interpolate.hpp).
      const float x0 = w.m[0] * qx[0] + w.m[1] * qy[0] + w.m[2],
                  y0 = w.m[3] * qx[0] + w.m[4] * qy[0] + w.m[5];
      EXPECT_EQ(ref[0], sample_bspline(im.view, x0, y0));
      for (int lanes : widths()) {
        std::fill(got.begin(), got.end(), -1.f);
        ASSERT_TRUE(lk_sample::sample_window_lanes(lanes, im.view, w, qx.data(), qy.data(), n, got.data()));
        EXPECT_EQ(0, std::memcmp(ref.data(), got.data(), n * sizeof(float))) << lanes << " lanes, n " << n;
        ++compared;
      }
    }
  }
  EXPECT_GE(compared, 400);
}

TEST(LkSample, EveryWidthRefusesAPointWithoutItsSixteenTaps) {
  std::mt19937 rng(5);
  const Image im = noise_image(40, 40, rng);
  const int side = 9, n = side * side;
  std::vector<float> qx(n), qy(n), out(n);
  for (int k = 0; k < n; ++k) {
    qx[k] = static_cast<float>(k % side - 4);
    qy[k] = static_cast<float>(k / side - 4);
  }
  // Centre x: the window spans centre +- 4, taps need [1, 37): inside for centres in [5, 33).
  for (float cx : {4.99f, 5.f, 32.99f, 33.f}) {
    const lk_sample::Warp w{{1, 0, cx, 0, 1, 20}};
    const bool expect = cx >= 5.f && cx < 33.f;
    for (int lanes : widths())
      EXPECT_EQ(expect,
                lk_sample::sample_window_lanes(lanes, im.view, w, qx.data(), qy.data(), n, out.data()))
          << cx << ", " << lanes << " lanes";
  }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const lk_sample::Warp degenerate{{nan, 0, 20, 0, 1, 20}};
  for (int lanes : widths())
    EXPECT_FALSE(
        lk_sample::sample_window_lanes(lanes, im.view, degenerate, qx.data(), qy.data(), n, out.data()))
        << lanes << " lanes";
}

}  // namespace
}  // namespace naneye::recon::scene
