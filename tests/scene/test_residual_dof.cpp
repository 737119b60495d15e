// The dense residual test's degrees of freedom read off a pair (effective_dof, dense_match.hpp):
// from chi-square samples of known nu, the 15.87 % quantile against the median gives nu back; a
// heavier upper tail (wrong matches) does not move it; no spread gives infinity.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "naneye/recon/scene/dense_match.hpp"

namespace naneye::recon::scene {
namespace {

double estimate(std::vector<double> v) {
  const auto m = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), m, v.end());
  const double median = *m;
  const auto q =
      v.begin() + static_cast<std::ptrdiff_t>(kResidualLowerQuantile * static_cast<double>(v.size()));
  std::nth_element(v.begin(), q, m);
  return effective_dof(*q, median);
}

TEST(ResidualDof, TheLowerSpreadOfChiSquareSamplesGivesTheirDegreesOfFreedom) {
  std::mt19937_64 rng(5);
  for (const double nu : {4.0, 15.0, 46.0}) {
    std::chi_squared_distribution<double> chi(nu);
    std::vector<double> v(20000);
    for (double& x : v) x = chi(rng) / nu;
    const double got = estimate(v);
    // The 15.87 % quantile of 20 000 samples: ~1 % standard error on it, ~4-6 % on nu; and
    // Wilson-Hilferty's own error at nu = 4.
    EXPECT_NEAR(got, nu, 0.12 * nu) << nu;
    // A fifth of the windows wrong (residuals 3-10x): the median moves, the lower spread hardly.
    std::uniform_real_distribution<double> wrong(3.0, 10.0);
    for (std::size_t k = 0; k < v.size() / 5; ++k) v[k] *= wrong(rng);
    EXPECT_GT(estimate(v), 0.7 * nu) << nu;
  }
  EXPECT_TRUE(std::isinf(effective_dof(1.0, 1.0)));
  EXPECT_TRUE(std::isinf(effective_dof(0.0, 1.0)));
}

}  // namespace
}  // namespace naneye::recon::scene
