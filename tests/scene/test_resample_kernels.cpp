// The dense path's rectification kernel (recon/scene/resample_kernels.hpp): the plain loop is Keys'
// cubic of interpolate.hpp at each tap's position, every SIMD width gives its bits, invalid taps give 0.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "../../recon/corners/simd.hpp"
#include "../../recon/scene/interpolate.hpp"
#include "../../recon/scene/resample_kernels.hpp"

namespace naneye::recon::scene {
namespace {

TEST(ResampleKernels, EveryWidthGivesTheCubicsBitsAndInvalidTapsGiveZero) {
  std::mt19937 rng(7);
  const int w = 37, h = 29;
  std::vector<float> raw(static_cast<std::size_t>(w) * h);
  std::uniform_real_distribution<float> level(0.f, 1023.f), frac(0.f, 1.f);
  for (float& v : raw) v = level(rng);
  const GrayView view{raw.data(), w, h};
  // 1003 pixels (not a multiple of any width: the tails run too), a sixth invalid.
  const std::size_t n = 1003;
  std::vector<int> tap(n);
  std::vector<float> fx(n), fy(n);
  std::uniform_int_distribution<int> col(1, w - 3), row(1, h - 3);
  for (std::size_t i = 0; i < n; ++i) {
    tap[i] = rng() % 6 == 0 ? -1 : row(rng) * w + col(rng);
    fx[i] = frac(rng);
    fy[i] = frac(rng);
  }
  std::vector<float> plain(n, -1.f);
  resample::taps_lanes(1, raw.data(), w, tap.data(), fx.data(), fy.data(), n, plain.data());
  int invalid = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (tap[i] < 0) {
      EXPECT_EQ(plain[i], 0.f);
      ++invalid;
      continue;
    }
    const double x = tap[i] % w + double(fx[i]), y = tap[i] / w + double(fy[i]);
    ASSERT_EQ(plain[i], sample_cubic(view, x, y)) << i;
  }
  EXPECT_GT(invalid, 100);
  std::vector<int> widths{4};
  if (simd::has_avx2()) widths.push_back(8);
  for (const int lanes : widths) {
    std::vector<float> out(n, -1.f);
    resample::taps_lanes(lanes, raw.data(), w, tap.data(), fx.data(), fy.data(), n, out.data());
    EXPECT_EQ(std::memcmp(out.data(), plain.data(), n * sizeof(float)), 0) << lanes << " lanes";
  }
  // The dispatching entry point is one of them.
  std::vector<float> out(n, -1.f);
  resample::taps(raw.data(), w, tap.data(), fx.data(), fy.data(), n, out.data());
  EXPECT_EQ(std::memcmp(out.data(), plain.data(), n * sizeof(float)), 0);
}

}  // namespace
}  // namespace naneye::recon::scene
