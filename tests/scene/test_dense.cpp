// Dense scene depth (recon/scene/dense.hpp) on the textured scenes against their truth.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "naneye/recon/camera/fixed_pattern.hpp"
#include "naneye/recon/scene/dense.hpp"
#include "naneye/sim/flat_field.hpp"
#include "scene_fixture.hpp"

namespace naneye {
namespace {

struct DenseFigures {
  int truth_visible = 0, covered = 0, unseen = 0, outside = 0, valid = 0, bad5 = 0, inliers = 0;
  double abs_rel = 0, rel_rms = 0, z_rms = 0;
  double mean_z = 0;  // mm, of the covered pixels' truth
};

// Mean |dZ|/Z that a mean disparity error of `px` gives at the covered pixels' mean depth (Z / (f B)
// per px of disparity, f B = 235.5 px mm).
double depth_error_bound(const DenseFigures& f, double px) {
  return px * f.mean_z / 235.5;
}

DenseFigures evaluate(const recon::scene::DepthMap& map, const cv::Mat& truth, const recon::StereoRig& rig) {
  DenseFigures f;
  double rel2 = 0, z2 = 0, rel = 0;
  for (int r = 0; r < map.height; ++r)
    for (int c = 0; c < map.width; ++c) {
      const double zt = truth.at<double>(r, c);
      const float z = map.z_at(c, r);
      f.truth_visible += std::isfinite(zt);
      if (std::isnan(z)) {
        EXPECT_TRUE(std::isnan(map.sigma_at(c, r)));
        continue;
      }
      ++f.valid;
      if (!rig.left.in_domain(Eigen::Vector2d(c, r))) ++f.outside;
      if (!std::isfinite(zt)) {
        ++f.unseen;
        continue;
      }
      ++f.covered;
      f.mean_z += zt;
      const double e = z - zt;
      rel += std::abs(e) / zt;
      if (std::abs(e) / zt > 0.05) {
        ++f.bad5;
        continue;
      }
      ++f.inliers;
      rel2 += (e / zt) * (e / zt);
      z2 += (e / map.sigma_at(c, r)) * (e / map.sigma_at(c, r));
    }
  f.abs_rel = rel / std::max(1, f.covered);
  f.mean_z /= std::max(1, f.covered);
  f.rel_rms = std::sqrt(rel2 / std::max(1, f.inliers));
  f.z_rms = std::sqrt(z2 / std::max(1, f.inliers));
  return f;
}

DenseFigures run(const sim::TexturedPair& p, bool bayer, recon::scene::DepthMap& map, const char* label) {
  const auto& rig = test::paper_d3();
  recon::scene::SparseReconstructor sr(rig);
  sr.load_luma(sim::raw_view(p.left, bayer), sim::raw_view(p.right, bayer));
  recon::scene::SparseResult seed;
  sr.reconstruct(sr.luma(), seed);
  recon::scene::DenseReconstructor dr(rig);
  dr.reconstruct(sr.luma(), map, &seed);  // as naneyed calls it (the band from the seed is off by default)
  const DenseFigures f = evaluate(map, p.depth, rig);
  std::printf(
      "%-22s %-5s truth-visible %5d valid %5d coverage %.1f %%  unseen %d outside %d  bad-5 %.2f %%  "
      "abs_rel %.3f %%  rel rms %.3f %%  rms(err/sigma) %.2f  share %.2f median %.1f mm\n",
      label, bayer ? "bayer" : "mono", f.truth_visible, f.valid,
      100.0 * f.covered / std::max(1, f.truth_visible), f.unseen, f.outside,
      100.0 * f.bad5 / std::max(1, f.covered), 100 * f.abs_rel, 100 * f.rel_rms, f.z_rms, map.valid_share,
      map.median_mm);
  return f;
}

// What every dense map must hold, whatever the scene and sensor: nothing beyond the fold, no depth
// where the right eye cannot see the surface (<= 1 %), <= 1 % of depths off by more than 5 %, the
// sigma neither much too small nor much too large, and the map's own figures consistent.
void expect_honest(const DenseFigures& f, const recon::scene::DepthMap& map, double max_z_rms,
                   double max_bad5) {
  EXPECT_EQ(f.outside, 0);
  EXPECT_LE(f.unseen, 0.01 * f.valid);
  EXPECT_LE(f.bad5, max_bad5 * f.covered);
  EXPECT_GE(f.z_rms, 0.7);
  EXPECT_LE(f.z_rms, max_z_rms);
  EXPECT_EQ(map.valid_count, f.valid);
  EXPECT_NEAR(map.valid_share, static_cast<double>(map.valid_count) / map.visible_count, 1e-12);
}

class DenseScene : public ::testing::TestWithParam<std::tuple<std::string, bool>> {};

// The targets: coverage >= 80 % of the pixels both eyes see, <= 1 % bad-5 and rms(err/sigma)
// within 0.7-1.4. Met on the mono plane, plane-far, sphere and height renders (93-95 %); Bayer
// covers 78-85 % on those since the residual test reads its spread off the pair (effective_dof:
// was ~71 %), held to 75 %; NOT yet where the texture is weak against the noise (the tube's dark
// far end: 68 % mono, 63 % Bayer at r 6). rms(err/sigma) measures 0.95-1.10 on every preset, the tube
// included (the Bayer tube 1.17 at r 6, the window's cap since 2026-12-06 late), since the fit takes the left
// image's gradient (1.18-1.42 before, the tube's the worst: the right gradient's shared noise, docs/scene.md
// "The gradient from the left"). The tube is held to what the method gives today (coverage >= 50 %, bad-5 <=
// 2 %), not to the target, so that a regression shows; docs/scene.md lists the gap.
TEST_P(DenseScene, AgainstTruth) {
  const auto& [name, bayer] = GetParam();
  const auto& p = test::textured_pair(name, bayer);
  recon::scene::DepthMap map;
  const DenseFigures f = run(p, bayer, map, name.c_str());
  const bool target = name != "tube";
  const double coverage = static_cast<double>(f.covered) / std::max(1, f.truth_visible);
  EXPECT_GE(coverage, !target ? 0.50 : bayer ? 0.75 : 0.80);
  expect_honest(f, map, 1.4, target ? 0.01 : 0.02);
  // Depth error: a mean disparity error within 3x the sparse path's measured 0.024 px rms (0.07
  // px); the tube (grazing walls, a dark far end), 0.12 px: measured 0.10.
  EXPECT_LE(f.abs_rel, depth_error_bound(f, name == "tube" ? 0.12 : 0.07));
}

INSTANTIATE_TEST_SUITE_P(Presets, DenseScene, test::every_preset(), test::preset_case_name);

// Decisions from the pair's own statistics, not from this simulator's defaults: the same honesty
// under other imaging, paired changes (a render costs ~0.2 s): darker and weaker texture; more blur
// and more noise; unequal Bayer gains.
struct Imaging {
  const char* label;
  bool bayer;
  void (*edit)(sim::SensorSettings&, sim::TexturedSceneSettings&);
};

class DenseImaging : public ::testing::TestWithParam<Imaging> {};

TEST_P(DenseImaging, HonestOnTheSphere) {
  const Imaging& c = GetParam();
  sim::SensorSettings sensor;
  sensor.bayer = c.bayer;
  sim::TexturedSceneSettings scene = *sim::textured_preset("sphere");
  c.edit(sensor, scene);
  const sim::TexturedRenderer renderer(test::paper_d3(), sensor);
  sim::Rng rng(11);
  const sim::TexturedPair p = renderer.render(scene, rng);
  recon::scene::DepthMap map;
  const DenseFigures f = run(p, c.bayer, map, c.label);
  // rms(err/sigma) 0.96-0.99 on all four since the fit takes the left image's gradient (dim or
  // blurred and noisy measured 1.43-1.45 before: the right gradient's noise, shared with its samples,
  // biased the step at low signal to noise; docs/scene.md, "The gradient from the left").
  expect_honest(f, map, 1.4, 0.01);
  // The 80 % (75 % Bayer) held here (80.8 and 83.5 %) only while those sigmas were 1.5x too
  // small: with the honest sigma the basin bound (max_sigma_px) refuses the faintest windows and the
  // two mono conditions cover 72.5 and 76.8 % at a fixed r = 3, 83.8 and 85.3 % with the radius
  // chosen per pair (r > 3 there); 79.7 and 79.5 % since the left gradient's sigma (the measured
  // sensor: 72.8 %), and 82.8 and 82.2 % (74.5 %) since the window's cap is 6 (r 6 on all three):
  // the 80 % again, the measured sensor held to what the fixed window gave, so that a
  // regression shows; docs/scene.md lists the gap.
  const bool measured = std::string(c.label) == "measured_sensor";
  EXPECT_GE(static_cast<double>(f.covered) / std::max(1, f.truth_visible), measured  ? 0.70
                                                                           : c.bayer ? 0.75
                                                                                     : 0.8);
}

// The window's cap (MatcherSettings::max_radius) at the measured sensor, where every pair grows to
// it: a curved surface's misfit grows with the window and is not in the sigma, the tube's the most
// (bench_dense_sigma --real-sensor: rms(err/sigma) 1.13 at a cap of 5, 1.22 at 6, 1.37 at 7). Its
// coverage is the blur's (docs/scene.md, "What any matcher could give": 25 % at most), held to what
// the cap of 6 gives less a margin, so that a regression shows. This render: rms(err/sigma) 1.10 /
// 1.21 / 1.37 and coverage 14.8 / 18.1 / 19.6 % at a cap of 5 / 6 / 7; held to 1.3, which a cap of
// 7 fails.
TEST(DenseMeasuredSensor, TubeSigmaHoldsAtTheWindowCap) {
  const sim::TexturedRenderer renderer(test::paper_d3(), sim::SensorSettings::measured(false));
  sim::Rng rng(11);
  const sim::TexturedPair p = renderer.render(*sim::textured_preset("tube"), rng);
  recon::scene::DepthMap map;
  const DenseFigures f = run(p, false, map, "tube measured");
  expect_honest(f, map, 1.3, 0.02);
  EXPECT_GE(static_cast<double>(f.covered) / std::max(1, f.truth_visible), 0.15);
}

// The measured sensor's fixed pattern (DSNU 3.8 DN, PRNU 2 %, column FPN) is noise the eyes do not
// share: measured from 64 capped and 64 flat frames of the same die and removed
// (recon/camera/fixed_pattern.hpp), the sphere's coverage passes the 80 % with honest sigmas.
// This render: 74.5 % as it comes, 83.6 % with the pattern removed, rms(err/sigma) 0.96 -> 0.98
// (bench_scene --seeds 3 --real-sensor [--fixed-pattern 64]: 77.5 -> 85.2 %).
TEST(DenseMeasuredSensor, FixedPatternRemovedTheSphereReachesTheTarget) {
  const sim::SensorSettings sensor = sim::SensorSettings::measured(false);
  const sim::TexturedRenderer renderer(test::paper_d3(), sensor);
  sim::Rng rng(11);
  const sim::TexturedPair p = renderer.render(*sim::textured_preset("sphere"), rng);
  recon::scene::DepthMap map;
  const DenseFigures raw = run(p, false, map, "sphere measured");
  const recon::StereoFixedPattern pattern = sim::measure_fixed_pattern(sensor, 64, 0.7, 5);
  sim::TexturedPair fixed{p.left.clone(), p.right.clone(), p.depth};
  recon::remove_fixed_pattern(pattern.left, sim::raw_view(p.left), fixed.left.ptr<std::uint16_t>());
  recon::remove_fixed_pattern(pattern.right, sim::raw_view(p.right), fixed.right.ptr<std::uint16_t>());
  const DenseFigures f = run(fixed, false, map, "sphere measured, fixed");
  expect_honest(f, map, 1.4, 0.01);
  const double before = static_cast<double>(raw.covered) / raw.truth_visible;
  const double after = static_cast<double>(f.covered) / f.truth_visible;
  EXPECT_GE(after, 0.80);
  EXPECT_GE(after - before, 0.04);
}

INSTANTIATE_TEST_SUITE_P(Conditions, DenseImaging,
                         ::testing::Values(Imaging{"dim_low_contrast", false,
                                                   [](sim::SensorSettings& s, sim::TexturedSceneSettings& t) {
                                                     s.white_dn =
                                                         300;  // DN; the default exposure's white is 760
                                                     t.texture.contrast *= 0.5;
                                                   }},
                                           Imaging{"blur_noise", false,
                                                   [](sim::SensorSettings& s, sim::TexturedSceneSettings&) {
                                                     s.defocus_sigma_px = 0.9;  // px; the default is 0.35
                                                     s.gain_e_per_dn =
                                                         3;  // e/DN; 4x the default's shot-noise variance
                                                   }},
                                           Imaging{"measured_sensor", false,
                                                   [](sim::SensorSettings& s, sim::TexturedSceneSettings&) {
                                                     // The real NanEye's blur, noise and fixed
                                                     // patterns (SensorSettings::measured).
                                                     s = sim::SensorSettings::measured(false);
                                                   }},
                                           Imaging{"bayer_gains", true,
                                                   [](sim::SensorSettings& s, sim::TexturedSceneSettings&) {
                                                     s.channel_gain = {0.5, 1.0, 0.9};
                                                   }}),
                         [](const auto& info) { return std::string(info.param.label); });

}  // namespace
}  // namespace naneye
