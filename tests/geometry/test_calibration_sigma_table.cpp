// CalibrationSigmaTable against the exact propagation it tabulates (CalibrationUncertainty), on every
// pixel both eyes see at depths across the dense band.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <utility>
#include <vector>

#include "../support/correlated_covariance.hpp"
#include "../support/paper_rig.hpp"
#include "naneye/recon/geometry/calibration_sigma_table.hpp"

namespace naneye::recon {
namespace calibration_sigma_table_test {

struct Errors {
  std::vector<double> rel;  // |table - exact| / exact
  int missing = 0;          // pixels both eyes see that the table gave no sigma
  double quantile(double q) {
    if (rel.empty()) return NAN;
    auto k = rel.begin() + static_cast<std::ptrdiff_t>(q * static_cast<double>(rel.size() - 1));
    std::nth_element(rel.begin(), k, rel.end());
    return *k;
  }
};

// Every `stride`-th pixel of the left raw grid whose point at depth z both eyes see (inside both
// models' domains, projecting into the right image).
Errors compare(const StereoRig& rig, const CalibrationUncertainty& u, const CalibrationSigmaTable& t,
               const std::vector<double>& depths, int stride) {
  Errors e;
  const double right_fold = rig.right.fold_radius_undistorted().value_or(INFINITY);
  for (double z : depths)
    for (int v = 0; v < rig.left.height(); v += stride)
      for (int c = 0; c < rig.left.width(); c += stride) {
        const Undistorted l = rig.left.undistort({c, v});
        if (!l.ok()) continue;
        const Eigen::Vector3d X(l.normalized.x() * z, l.normalized.y() * z, z);
        const Eigen::Vector3d Xr = rig.R * X + rig.T;
        if (!(Xr.z() > 0) || (Xr.head<2>() / Xr.z()).norm() >= right_fold) continue;
        const Eigen::Vector2d pr = rig.right.project(Xr);
        if (pr.x() < 0 || pr.y() < 0 || pr.x() > rig.right.width() - 1 || pr.y() > rig.right.height() - 1)
          continue;
        const double exact = u.depth_sigma_mm(X), got = t.depth_sigma_mm(c, v, X);
        if (!std::isfinite(got)) {
          ++e.missing;
          continue;
        }
        e.rel.push_back(std::abs(got - exact) / exact);
      }
  return e;
}

// The default table (8 Chebyshev terms in inverse depth per pixel) against the exact propagation on
// every other pixel both eyes see, at depths across the band and at its very ends, for two
// covariances (different correlations, one widened by a cross-validation scale). Measured:
// max 1.9e-4 of the sigma (4 terms 1.1e-2, 6 terms 1.8e-3, 10 terms 3.2e-5; docs/scene.md); the
// bound 1e-3 leaves room for other rigs' covariances without letting a coarser table through.
TEST(CalibrationSigmaTable, MatchesTheExactPropagationOnEveryPixelBothEyesSee) {
  for (const auto& [seed, scale] : {std::pair{3u, 1.0}, std::pair{11u, 2.64}}) {
    StereoRig rig = test::paper_d3();
    rig.sigmas.covariance = test::correlated_covariance(rig, 1.0, seed);
    rig.sigmas.covariance_scale = scale;
    const auto u = CalibrationUncertainty::of(rig);
    ASSERT_TRUE(u.has_value());
    const auto t = CalibrationSigmaTable::of(rig);
    ASSERT_TRUE(t.has_value());
    Errors e = compare(rig, *u, *t, {5.01, 5.5, 8, 12, 20, 33, 55, 90, 140, 149.9}, 2);
    const double p50 = e.quantile(0.5), p99 = e.quantile(0.99), worst = e.quantile(1.0);
    std::printf(
        "covariance seed %u, scale %.2f: %zu points, |table - exact| / exact p50 %.1e, p99 %.1e, max %.1e\n",
        seed, scale, e.rel.size(), p50, p99, worst);
    EXPECT_GT(e.rel.size(), 100000u);
    EXPECT_EQ(e.missing, 0);
    EXPECT_LT(worst, 1e-3);
  }
}

// Where the table holds nothing (depths beyond its band, pixels beyond the fold or the image) the
// exact propagation answers, to the float.
TEST(CalibrationSigmaTable, OutsideTheTableTheExactPropagationAnswers) {
  StereoRig rig = test::paper_d3();
  rig.sigmas.covariance = test::correlated_covariance(rig, 1.0, 3);
  const auto u = CalibrationUncertainty::of(rig);
  CalibrationSigmaTableSettings s;
  s.z_min_mm = 10;
  s.z_max_mm = 40;
  s.depth_terms = 4;
  const CalibrationSigmaTable t(rig, *u, s);
  const auto on_ray = [&](int c, int v, double z) {
    const Undistorted l = rig.left.undistort({c, v});
    EXPECT_TRUE(l.ok());
    return Eigen::Vector3d(l.normalized.x() * z, l.normalized.y() * z, z);
  };
  for (double z : {5.0, 9.99, 40.01, 80.0}) {
    const Eigen::Vector3d X = on_ray(125, 125, z);
    EXPECT_EQ(t.depth_sigma_mm(125, 125, X), static_cast<float>(u->depth_sigma_mm(X))) << z;
  }
  // Inside the band the 4-term table is close but not exact: the table answers there.
  const Eigen::Vector3d inside = on_ray(125, 125, 20);
  EXPECT_NE(t.depth_sigma_mm(125, 125, inside), static_cast<float>(u->depth_sigma_mm(inside)));
  EXPECT_NEAR(t.depth_sigma_mm(125, 125, inside), u->depth_sigma_mm(inside),
              0.02 * u->depth_sigma_mm(inside));
  // The image's corner lies beyond the left fold (177 px from the centre, the fold at 138.6 px): no
  // ray was tabulated there; and a pixel outside the image.
  ASSERT_FALSE(rig.left.undistort({0, 0}).ok());
  const Eigen::Vector3d X(-3, -3, 20);
  EXPECT_EQ(t.depth_sigma_mm(0, 0, X), static_cast<float>(u->depth_sigma_mm(X)));
  EXPECT_EQ(t.depth_sigma_mm(-1, 40, X), static_cast<float>(u->depth_sigma_mm(X)));
  EXPECT_EQ(t.depth_sigma_mm(40, 250, X), static_cast<float>(u->depth_sigma_mm(X)));
}

TEST(CalibrationSigmaTable, NoneWithoutACovarianceAndSettingsThatCannotWorkAreRefused) {
  EXPECT_FALSE(CalibrationSigmaTable::of(test::paper_d3()).has_value());  // marginal sigmas only
  const auto refused = [](auto change) {
    CalibrationSigmaTableSettings s;
    change(s);
    EXPECT_THROW(s.validate(), std::invalid_argument);
  };
  refused([](auto& s) { s.z_min_mm = 0; });
  refused([](auto& s) { s.z_max_mm = s.z_min_mm; });
  refused([](auto& s) { s.z_max_mm = INFINITY; });
  refused([](auto& s) { s.depth_terms = 1; });
  refused([](auto& s) { s.depth_terms = 33; });
  EXPECT_NO_THROW(CalibrationSigmaTableSettings{}.validate());
}

}  // namespace calibration_sigma_table_test
}  // namespace naneye::recon
