// The LK's small positive-definite factor (recon/scene/spd_factor.hpp): the solutions Eigen's
// pivoting LDLT gives on well- and ill-conditioned matrices, and the refusals Eigen's
// isPositive() / vectorD() made before it (indefinite, singular, NaN).
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "../../recon/scene/spd_factor.hpp"

namespace naneye::recon::scene {
namespace {

using M6 = Eigen::Matrix<double, 6, 6>;
using V6 = Eigen::Matrix<double, 6, 1>;

// A sum of `terms` random outer products scaled per coordinate like the affine LK's Hessian (the
// linear part's entries ~ q^2 = up to 36 times the translation's): condition numbers up to ~1e6.
M6 lk_like(std::mt19937& rng, int terms) {
  std::normal_distribution<double> g(0, 1);
  M6 h = M6::Zero();
  for (int k = 0; k < terms; ++k) {
    V6 a;
    for (int i = 0; i < 6; ++i) a(i) = g(rng) * (i < 4 ? 6.0 : 1.0);
    h += a * a.transpose();
  }
  return h;
}

TEST(SpdFactor, SolvesAsEigensLdltDoes) {
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0, 1);
  double worst = 0;
  for (int trial = 0; trial < 500; ++trial) {
    // 7..40 terms: from barely full rank (the worst conditioned) to a whole window.
    const M6 h = lk_like(rng, 7 + trial % 34);
    V6 b;
    for (int i = 0; i < 6; ++i) b(i) = g(rng);
    SpdFactor<6> f;
    ASSERT_TRUE(f.factor(h)) << h;
    const V6 ours = f.solve(b), eigen = h.ldlt().solve(b);
    // Both backward stable: their difference is within the condition number times the rounding.
    Eigen::JacobiSVD<M6> svd(h);
    const double cond = svd.singularValues()(0) / svd.singularValues()(5);
    const double rel = (ours - eigen).norm() / eigen.norm() / (cond * std::numeric_limits<double>::epsilon());
    worst = std::max(worst, rel);
  }
  std::printf("worst |ours - Eigen| / |x| in units of cond * eps: %.3f\n", worst);
  EXPECT_LT(worst, 10.0);
}

TEST(SpdFactor, RefusesWhatIsNotPositiveDefinite) {
  std::mt19937 rng(9);
  SpdFactor<6> f;
  const M6 h = lk_like(rng, 20);
  ASSERT_TRUE(f.factor(h));
  // Singular: a parameter the window does not constrain at all (its row and column zero).
  M6 singular = h;
  singular.row(2).setZero();
  singular.col(2).setZero();
  EXPECT_FALSE(f.factor(singular));
  // Indefinite: one direction pulled below zero, as the noise part's subtraction can.
  const Eigen::SelfAdjointEigenSolver<M6> eig(h);
  const V6 v = eig.eigenvectors().col(0);
  EXPECT_FALSE(f.factor(h - 2 * eig.eigenvalues()(0) * v * v.transpose()));
  EXPECT_FALSE(f.factor(-h));
  M6 nan = h;
  nan(3, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(f.factor(nan));
  // The identity and a diagonal are solved exactly.
  ASSERT_TRUE(f.factor(M6::Identity() * 4));
  EXPECT_EQ(f.solve(V6::Constant(2)), V6::Constant(0.5));
}

}  // namespace
}  // namespace naneye::recon::scene
