// The dense map's calibration sigma (DepthMap::calib_sigma_mm) against the exact propagation at every
// depth it gives, and nothing else of the map changed by it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "../support/correlated_covariance.hpp"
#include "naneye/recon/geometry/calibration_uncertainty.hpp"
#include "naneye/recon/scene/dense.hpp"
#include "scene_fixture.hpp"

namespace naneye {
namespace dense_calib_sigma_test {

recon::scene::DepthMap dense_map(const recon::StereoRig& rig, const sim::TexturedPair& p) {
  recon::scene::SparseReconstructor sr(rig);
  sr.load_luma(sim::raw_view(p.left, false), sim::raw_view(p.right, false));
  recon::scene::DenseReconstructor dr(rig);
  recon::scene::DepthMap map;
  dr.reconstruct(sr.luma(), map);
  return map;
}

TEST(DenseCalibSigma, EveryDepthCarriesTheSigmaItsCalibrationAllows) {
  const sim::TexturedPair& p = test::textured_pair("sphere", false);
  const recon::scene::DepthMap plain = dense_map(test::paper_d3(), p);
  // The paper's file: marginal sigmas only, no covariance, so no calibration sigma anywhere.
  ASSERT_GT(plain.valid_count, 30000);
  EXPECT_TRUE(std::all_of(plain.calib_sigma_mm.begin(), plain.calib_sigma_mm.end(),
                          [](float s) { return std::isnan(s); }));
  EXPECT_TRUE(std::isnan(plain.calib_sigma_median_mm));

  recon::StereoRig rig = test::paper_d3();
  rig.sigmas.covariance = test::correlated_covariance(rig, 0.1, 5);
  const auto u = recon::CalibrationUncertainty::of(rig);
  ASSERT_TRUE(u.has_value());
  const recon::scene::DepthMap map = dense_map(rig, p);
  // The covariance changes no depth and no match sigma, bit for bit.
  ASSERT_EQ(map.valid_count, plain.valid_count);
  for (std::size_t i = 0; i < map.z_mm.size(); ++i) {
    ASSERT_EQ(std::isnan(map.z_mm[i]), std::isnan(plain.z_mm[i])) << i;
    if (std::isnan(map.z_mm[i])) {
      EXPECT_TRUE(std::isnan(map.calib_sigma_mm[i])) << i;
      continue;
    }
    ASSERT_EQ(map.z_mm[i], plain.z_mm[i]) << i;
    ASSERT_EQ(map.sigma_mm[i], plain.sigma_mm[i]) << i;
  }
  // Every depth's calibration sigma is the exact propagation's at its point (the pixel's ray at the
  // map's depth) within the table's 1e-3.
  std::vector<double> exact;
  double worst = 0, ratio = 0;
  for (int r = 0; r < map.height; ++r)
    for (int c = 0; c < map.width; ++c) {
      const float z = map.z_at(c, r);
      if (std::isnan(z)) continue;
      const recon::Undistorted ray = rig.left.undistort({c, r});
      ASSERT_TRUE(ray.ok());
      const double want = u->depth_sigma_mm({ray.normalized.x() * z, ray.normalized.y() * z, z});
      worst = std::max(worst, std::abs(map.calib_sigma_at(c, r) - want) / want);
      ratio += map.calib_sigma_at(c, r) / map.sigma_at(c, r);
      exact.push_back(want);
    }
  std::nth_element(exact.begin(), exact.begin() + static_cast<std::ptrdiff_t>(exact.size() / 2), exact.end());
  const double median = exact[exact.size() / 2];
  std::printf(
      "sphere mono: %zu depths, calibration sigma median %.4f mm (exact %.4f), worst |map - exact| / "
      "exact %.1e, mean calibration / match sigma %.2f\n",
      exact.size(), map.calib_sigma_median_mm, median, worst, ratio / static_cast<double>(exact.size()));
  EXPECT_LT(worst, 1e-3);
  EXPECT_NEAR(map.calib_sigma_median_mm, median, 1e-3 * median);
}

}  // namespace dense_calib_sigma_test
}  // namespace naneye
