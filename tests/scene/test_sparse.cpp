// Sparse scene reconstruction (recon/scene/sparse.hpp) on the textured scenes against their truth.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "naneye/recon/scene/sparse.hpp"
#include "scene_fixture.hpp"

namespace naneye {
namespace {

struct SparseFigures {
  int features = 0, valid = 0, outliers = 0, unseen = 0, outside = 0;
  double rel_rms = 0, z_rms = 0;  // over the inliers
};

// Outlier: relative depth error above 5 % (the bad-5 % line).
SparseFigures evaluate_sparse(const std::string& name, bool bayer, recon::scene::SparseResult& res) {
  const auto& rig = test::paper_d3();
  const auto& p = test::textured_pair(name, bayer);
  recon::scene::SparseReconstructor sr(rig);
  sr.reconstruct(sim::raw_view(p.left, bayer), sim::raw_view(p.right, bayer), res);
  SparseFigures f;
  f.features = static_cast<int>(res.points.size());
  double rel2 = 0, z2 = 0;
  int inl = 0;
  for (const auto& q : res.points) {
    // The paper's file has no covariance: no calibration sigma to give.
    EXPECT_TRUE(std::isnan(q.calib_sigma_mm));
    if (!q.valid()) {
      EXPECT_TRUE(std::isnan(q.X.z()));
      continue;
    }
    ++f.valid;
    if (!rig.left.in_domain(q.left_px) || !rig.right.in_domain(q.right_px)) ++f.outside;
    const double zt = p.depth.at<double>(static_cast<int>(q.left_px.y()), static_cast<int>(q.left_px.x()));
    if (std::isnan(zt)) {
      ++f.unseen;
      continue;
    }
    const double e = q.X.z() - zt;
    if (std::abs(e) / zt > 0.05) {
      ++f.outliers;
      continue;
    }
    ++inl;
    rel2 += (e / zt) * (e / zt);
    z2 += (e / q.depth_sigma_mm) * (e / q.depth_sigma_mm);
  }
  f.rel_rms = std::sqrt(rel2 / std::max(1, inl));
  f.z_rms = std::sqrt(z2 / std::max(1, inl));
  std::printf(
      "%-10s %-5s features %4d valid %4d outliers %3d unseen %d outside %d  depth err rms %.2f %%  "
      "rms(err/sigma) %.2f  noise %.2f DN\n",
      name.c_str(), bayer ? "bayer" : "mono", f.features, f.valid, f.outliers, f.unseen, f.outside,
      100 * f.rel_rms, f.z_rms, res.noise_sigma_dn);
  return f;
}

class SparseScene : public ::testing::TestWithParam<std::tuple<std::string, bool>> {};

TEST_P(SparseScene, AgainstTruth) {
  const auto& [name, bayer] = GetParam();
  recon::scene::SparseResult res;
  const SparseFigures f = evaluate_sparse(name, bayer, res);
  // No point where one eye cannot see the surface, none beyond a model's domain.
  EXPECT_EQ(f.unseen, 0);
  EXPECT_EQ(f.outside, 0);
  EXPECT_GE(f.valid - f.outliers, 300);
  EXPECT_LE(f.outliers, 0.01 * f.valid);
  // Sigmas that hold.
  EXPECT_GE(f.z_rms, 0.7);
  EXPECT_LE(f.z_rms, 1.4);
  // The wider LK windows where the affine holds (sparse_wide.cpp), seed 5: plane-far's depth error
  // is 0.57 % mono, 0.74 % Bayer with the 9 x 9 window alone, 0.41 % and 0.59 % with 13 x 13 (until
  // 2026-12-07), 0.27 % and 0.27 % nested to 21 x 21 (the Bayer fits' residual variance over its
  // true degrees of freedom, lk_affine.cpp, lets Bayer windows widen at all); and the height
  // field's curvature must keep them out: rms(err/sigma) 1.27 mono, 1.14 Bayer with 9 x 9 alone
  // (the Bayer figure rose from 1.02 when the scene luminance stopped repairing texture as defects,
  // 2026-12-05: less noise, the same curvature misfit), 1.68 mono and 1.34 Bayer with 13 x 13
  // everywhere, 1.18 and 1.09 nested to 21 x 21.
  if (name == "plane-far") {
    EXPECT_LE(f.rel_rms, 0.0035);
  }
  if (name == "height") {
    EXPECT_LE(f.z_rms, bayer ? 1.20 : 1.32);
  }
}

INSTANTIATE_TEST_SUITE_P(Presets, SparseScene, test::every_preset(), test::preset_case_name);

// With a calibration that carries its covariance, every valid point also gets the depth sigma the
// calibration allows there (CalibrationUncertainty at its X), and nothing else changes.
TEST(SparseCalibrationSigma, GivenForEveryValidPointWhenTheCalibrationHasACovariance) {
  recon::StereoRig rig = test::paper_d3();
  const auto what_if = recon::CalibrationUncertainty::assuming_independent_sigmas(rig);
  ASSERT_TRUE(what_if.has_value());
  rig.sigmas.covariance = what_if->covariance();  // any covariance will do for the plumbing
  const auto u = recon::CalibrationUncertainty::of(rig);
  ASSERT_TRUE(u.has_value());
  const auto& p = test::textured_pair("plane", false);
  recon::scene::SparseResult with, without;
  recon::scene::SparseReconstructor(rig).reconstruct(sim::raw_view(p.left, false),
                                                     sim::raw_view(p.right, false), with);
  recon::scene::SparseReconstructor(test::paper_d3())
      .reconstruct(sim::raw_view(p.left, false), sim::raw_view(p.right, false), without);
  ASSERT_EQ(with.points.size(), without.points.size());
  EXPECT_GE(with.valid_count, 300);
  for (std::size_t i = 0; i < with.points.size(); ++i) {
    const auto &a = with.points[i], &b = without.points[i];
    EXPECT_EQ(a.status, b.status);
    EXPECT_EQ(a.id, b.id);
    if (!a.valid()) {
      EXPECT_TRUE(std::isnan(a.calib_sigma_mm));
      continue;
    }
    EXPECT_EQ(a.right_px, b.right_px);
    EXPECT_EQ(a.X, b.X);
    EXPECT_EQ(a.depth_sigma_mm, b.depth_sigma_mm);
    EXPECT_EQ(a.calib_sigma_mm, u->depth_sigma_mm(a.X));
  }
}

// At a real NanEye's blur (edges 1.0-1.6 px, ../shared/notes/measurements.md; the presets are rendered
// at 0.41 px) the far plane's texture is faint and a fifth of its points carry depth sigmas of 2-4 %:
// given, 1-3 % of them land beyond 5 % of the truth. Flagged `imprecise` instead, none does, and
// every point given holds its depth to max_depth_sigma_rel.
TEST(SparseBlur, PointsTooImpreciseToStandBehindAreFlaggedNotGiven) {
  sim::SensorSettings sensor;
  sensor.defocus_sigma_px = 1.2;  // 1.22 px in all with the diffraction
  const sim::TexturedRenderer renderer(test::paper_d3(), sensor);
  const auto& rig = test::paper_d3();
  int outliers[2] = {0, 0}, valid[2] = {0, 0}, flagged = 0, inliers = 0;
  double z2 = 0;
  for (int k = 0; k < 3; ++k) {  // bench_scene's three renders
    const sim::TexturedPair p = sim::numbered_render(renderer, "plane-far", k);
    for (int flag = 0; flag < 2; ++flag) {
      recon::scene::SparseSettings s;
      if (!flag) s.max_depth_sigma_rel = std::numeric_limits<double>::infinity();
      recon::scene::SparseReconstructor sr(rig, s);
      recon::scene::SparseResult res;
      sr.reconstruct(sim::raw_view(p.left), sim::raw_view(p.right), res);
      for (const auto& q : res.points) {
        if (q.status == recon::scene::PointStatus::imprecise) {
          ++flagged;
          EXPECT_TRUE(std::isnan(q.X.z()));
          EXPECT_TRUE(flag);
        }
        if (!q.valid()) continue;
        ++valid[flag];
        if (flag) {
          EXPECT_LE(q.depth_sigma_mm, s.max_depth_sigma_rel * q.X.z());
        }
        const double zt =
            p.depth.at<double>(static_cast<int>(q.left_px.y()), static_cast<int>(q.left_px.x()));
        outliers[flag] += !(std::abs(q.X.z() - zt) <= 0.05 * zt);
        if (flag && std::abs(q.X.z() - zt) <= 0.05 * zt) {
          z2 += std::pow((q.X.z() - zt) / q.depth_sigma_mm, 2);
          ++inliers;
        }
      }
    }
  }
  std::printf(
      "plane-far, blur 1.22 px, 3 renders: all given %d points, %d beyond 5 %%; flagged: %d given, %d "
      "beyond 5 %%, %d imprecise\n",
      valid[0], outliers[0], valid[1], outliers[1], flagged);
  // What the flag is for: it takes most of the points beyond 5 % (2026-12-07: 16 of 1536 given
  // without it, 1 of 1477 with it; 33 and 4 before the curvature model and the interpolant's share).
  EXPECT_GE(outliers[0], 5 * std::max(1, outliers[1]));
  EXPECT_LE(outliers[1], 0.01 * valid[1]);
  EXPECT_GE(valid[1], 3 * 300);
  EXPECT_GT(flagged, 0);
  // Sigmas that hold at this blur too (the template's gradient noise in them, lk_affine.cpp).
  const double z_rms = std::sqrt(z2 / std::max(1, inliers));
  std::printf("rms(err/sigma) of the points given: %.2f\n", z_rms);
  EXPECT_GE(z_rms, 0.7);
  EXPECT_LE(z_rms, 1.4);
}

// Through the real NanEye's measured blur, noise and fixed patterns (SensorSettings::measured) the
// tube's texture is faint: with the coarse search on the raw mono pixels and a fixed final ZNCC of
// 0.9 it kept ~50 points per pair, its features refused as weak coarse matches (164 of ~390) and
// failed refinements. The search on the binomial luminance and the noise-residual acceptance
// (SparseSettings::search_binomial, final_noise_false_reject) must keep many more without an outlier
// more, and their sigmas must hold.
TEST(SparseRealSensor, FaintTubeKeepsItsPointsAndTheirSigmas) {
  const auto& rig = test::paper_d3();
  const sim::TexturedRenderer renderer(rig, sim::SensorSettings::measured(false));
  int valid[2] = {0, 0}, outliers[2] = {0, 0}, unseen = 0, inliers = 0;
  double z2 = 0;
  for (int k = 0; k < 2; ++k) {
    const sim::TexturedPair p = sim::numbered_render(renderer, "tube", k);
    for (int now = 0; now < 2; ++now) {
      recon::scene::SparseSettings s;
      if (!now) {
        s.search_binomial = false;
        s.final_noise_false_reject = 0;
      }
      recon::scene::SparseReconstructor sr(rig, s);
      recon::scene::SparseResult res;
      sr.reconstruct(sim::raw_view(p.left), sim::raw_view(p.right), res);
      for (const auto& q : res.points) {
        if (!q.valid()) continue;
        ++valid[now];
        const double zt =
            p.depth.at<double>(static_cast<int>(q.left_px.y()), static_cast<int>(q.left_px.x()));
        if (std::isnan(zt)) {
          unseen += now;
          continue;
        }
        const bool out = !(std::abs(q.X.z() - zt) <= 0.05 * zt);
        outliers[now] += out;
        if (now && !out) {
          z2 += std::pow((q.X.z() - zt) / q.depth_sigma_mm, 2);
          ++inliers;
        }
      }
    }
  }
  const double z_rms = std::sqrt(z2 / std::max(1, inliers));
  std::printf(
      "tube mono, measured sensor, 2 renders: before %d points (%d beyond 5 %%), now %d (%d), "
      "rms(err/sigma) %.2f\n",
      valid[0], outliers[0], valid[1], outliers[1], z_rms);
  EXPECT_GE(valid[1], 2 * valid[0]);
  EXPECT_EQ(unseen, 0);
  EXPECT_LE(outliers[1], std::max(1.0, 0.01 * valid[1]));
  EXPECT_GE(z_rms, 0.7);
  EXPECT_LE(z_rms, 1.4);
}

// The wider windows take the narrow one's acceptance (sparse_wide.cpp): a ZNCC of min_final_zncc, or
// a residual the noise explains. With the ZNCC alone (until 2026-12-07) none of the faint tube's
// wider windows below 0.9 was kept, and bench_scene --real-sensor --fixed-pattern 64 gave the tube
// 232 points per pair at 0.50 % depth error; with it, 271 at 0.43 %.
TEST(SparseRealSensor, FaintTubesWiderWindowsTakeTheNoiseAcceptanceToo) {
  const auto& rig = test::paper_d3();
  const sim::TexturedRenderer renderer(rig, sim::SensorSettings::measured(false));
  const recon::scene::SparseSettings s;
  int faint_wide = 0, good = 0;
  double z2 = 0;
  for (int k = 0; k < 2; ++k) {
    const sim::TexturedPair p = sim::numbered_render(renderer, "tube", k);
    recon::scene::SparseReconstructor sr(rig, s);
    recon::scene::SparseResult res;
    sr.reconstruct(sim::raw_view(p.left), sim::raw_view(p.right), res);
    for (const auto& q : res.points) {
      if (!q.valid() || q.window_radius_px <= s.lk.radius || q.zncc >= s.min_final_zncc) continue;
      ++faint_wide;
      const double zt = p.depth.at<double>(static_cast<int>(q.left_px.y()), static_cast<int>(q.left_px.x()));
      if (!(std::abs(q.X.z() - zt) <= 0.05 * zt)) continue;
      ++good;
      z2 += std::pow((q.X.z() - zt) / q.depth_sigma_mm, 2);
    }
  }
  const double z_rms = std::sqrt(z2 / std::max(1, good));
  std::printf(
      "tube mono, measured sensor, 2 renders: %d points from a wider window at ZNCC < %.2f, %d within "
      "5 %%, rms(err/sigma) %.2f\n",
      faint_wide, s.min_final_zncc, good, z_rms);
  EXPECT_GE(faint_wide, 20);
  EXPECT_EQ(good, faint_wide);
  EXPECT_GE(z_rms, 0.7);
  EXPECT_LE(z_rms, 1.4);
}

}  // namespace
}  // namespace naneye
