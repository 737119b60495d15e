// The affine LK's sums kernel (recon/scene/lk_dots.hpp): every width gives the plain loop's bits,
// the float sums hold the double ones to the precision the LK needs, and the centre keeps a window
// far from zero from cancelling.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "../../recon/corners/simd.hpp"
#include "../../recon/scene/lk_dots.hpp"

namespace naneye::recon::scene {
namespace {

std::vector<int> dot_widths() {
  std::vector<int> l{1, 4};
  if (simd::has_avx2()) l.push_back(8);
  return l;
}

// m + 1 arrays of n values (a first), zero-padded to a multiple of the block.
std::vector<std::vector<float>> random_dot_arrays(int m, int n, float offset, float spread,
                                                  std::mt19937& rng) {
  std::uniform_real_distribution<float> v(-spread, spread);
  const int n8 = lk_dots::padded(n);
  std::vector<std::vector<float>> out(static_cast<std::size_t>(m + 1), std::vector<float>(n8, 0.f));
  for (auto& row : out)
    for (int k = 0; k < n; ++k) row[static_cast<std::size_t>(k)] = v(rng);
  for (int k = 0; k < n; ++k) out[0][static_cast<std::size_t>(k)] += offset;
  return out;
}

TEST(LkDots, EveryWidthGivesThePlainLoopsBits) {
  std::mt19937 rng(5);
  int compared = 0;
  for (int n : {9, 49, 81, 121, 169, 225})  // the LK's windows: every tail length of 8 lanes
    for (int m = 0; m <= lk_dots::kMaxArrays; ++m) {
      const auto arrays = random_dot_arrays(m, n, 800.f, 40.f, rng);
      std::vector<const float*> b;
      for (int j = 1; j <= m; ++j) b.push_back(arrays[static_cast<std::size_t>(j)].data());
      const float c = 803.25f;
      const int n8 = lk_dots::padded(n);
      // The padding of a must equal the centre so that it adds nothing.
      std::vector<float> a = arrays[0];
      for (int k = n; k < n8; ++k) a[static_cast<std::size_t>(k)] = c;
      std::vector<double> ref(static_cast<std::size_t>(m + 1)), out(ref.size());
      lk_dots::dot_many_lanes(1, a.data(), c, b.data(), m, n8, ref.data());
      for (int lanes : dot_widths()) {
        lk_dots::dot_many_lanes(lanes, a.data(), c, b.data(), m, n8, out.data());
        for (std::size_t j = 0; j < ref.size(); ++j) {
          ASSERT_EQ(std::memcmp(&ref[j], &out[j], sizeof(double)), 0)
              << "n " << n << " m " << m << " lanes " << lanes << " sum " << j << ": " << ref[j] << " vs "
              << out[j];
          ++compared;
        }
      }
    }
  EXPECT_GT(compared, 200);
}

// Against double sums of the same floats: the LK's Hessian and gradient need ~1e-4 relative (its
// steps stop at 5e-3 px); the kernel's float partial sums give ~1e-6. The square of a window of
// mean 800 and contrast 40 about its centre keeps that precision; about 0 it would lose
// (800 / 40)^2 = 400 times more (the reason for the centre).
TEST(LkDots, FloatSumsHoldTheDoubleSums) {
  std::mt19937 rng(8);
  for (int n : {81, 169, 225}) {
    const int m = 8, n8 = lk_dots::padded(n);
    auto arrays = random_dot_arrays(m, n, 800.f, 40.f, rng);
    double mean = 0;
    for (int k = 0; k < n; ++k) mean += arrays[0][static_cast<std::size_t>(k)];
    mean /= n;
    const float c = static_cast<float>(mean);
    for (int k = n; k < n8; ++k) arrays[0][static_cast<std::size_t>(k)] = c;
    std::vector<const float*> b;
    for (int j = 1; j <= m; ++j) b.push_back(arrays[static_cast<std::size_t>(j)].data());
    std::vector<double> out(m + 1);
    lk_dots::dot_many(arrays[0].data(), c, b.data(), m, n8, out.data());
    double sq = 0;
    std::vector<double> ref(m, 0.0), scale(m, 0.0);
    for (int k = 0; k < n; ++k) {
      const double x = static_cast<double>(arrays[0][static_cast<std::size_t>(k)]) - c;
      sq += x * x;
      for (int j = 0; j < m; ++j) {
        const double y = arrays[static_cast<std::size_t>(j + 1)][static_cast<std::size_t>(k)];
        ref[static_cast<std::size_t>(j)] += x * y;
        scale[static_cast<std::size_t>(j)] += std::abs(x * y);
      }
    }
    EXPECT_NEAR(out[0], sq, 1e-5 * sq) << n;
    // A sum of mixed signs is held relative to the sum of its terms' sizes.
    for (int j = 0; j < m; ++j)
      EXPECT_NEAR(out[static_cast<std::size_t>(j + 1)], ref[static_cast<std::size_t>(j)],
                  1e-5 * scale[static_cast<std::size_t>(j)])
          << n << " " << j;
  }
}

}  // namespace
}  // namespace naneye::recon::scene
