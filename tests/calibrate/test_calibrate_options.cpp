// The calibration's options (fixed k3, tangential terms), one-eyed views, refusals, the YAML round trip
// of the result with its sigmas, and the two cross-validations.
#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "calib_scene.hpp"

using namespace naneye;

namespace {

// Dataset 1/2 style truth: the paper's Dataset 3 rig with k3 = 0 (so fixing it is the right model).
recon::StereoRig without_k3(const recon::StereoRig& rig) {
  recon::StereoRig out = rig;
  for (auto* cam : {&out.left, &out.right}) {
    recon::Distortion d = cam->distortion();
    d.k3 = 0;
    d.k2 = -0.05;  // keeps the fold beyond the image without k3
    *cam = recon::CameraModel(cam->K(), d, cam->width(), cam->height());
  }
  return out;
}

}  // namespace

TEST(CalibrateOptions, FixK3GivesZeroAndZeroSigma) {
  const recon::StereoRig truth = without_k3(test::paper_d3());
  const auto views = test::noisy_views(truth, test::sample_poses(truth, 12, 21), 0.1, 22);
  recon::CalibrationSettings s;
  s.fix_k3 = true;
  const auto res = recon::calibrate_stereo(views, test::recon_board(), s);
  ASSERT_TRUE(res.ok) << res.message;
  for (const char* eye : {"left", "right"}) {
    const auto* k3 = res.find(std::string(eye) + ".k3");
    EXPECT_TRUE(k3->fixed);
    EXPECT_EQ(k3->value, 0.0);
    EXPECT_EQ(k3->sigma, 0.0);
    const auto* k2 = res.find(std::string(eye) + ".k2");
    EXPECT_LE(std::abs(k2->value + 0.05), 3 * k2->sigma) << eye;
  }
  EXPECT_EQ(res.rig.left.distortion().k3, 0.0);
  EXPECT_EQ((*res.rig.sigmas.D1)(4), 0.0);
  EXPECT_EQ((*res.rig.sigmas.D2)(4), 0.0);
  // fx fy cx cy k1 k2 per camera (p1 p2 k3 fixed) + 6 for the stereo pose + 6 per view.
  EXPECT_EQ(res.free_parameters, 2 * 6 + 6 + 6 * 12);
}

TEST(CalibrateOptions, TangentialTermsRecovered) {
  recon::StereoRig truth = test::paper_d3();
  recon::Distortion d = truth.left.distortion();
  d.p1 = 0.003;
  d.p2 = -0.002;
  truth.left = recon::CameraModel(truth.left.K(), d, 250, 250);
  const auto views = test::noisy_views(truth, test::sample_poses(truth, 14, 31), 0.1, 32);
  recon::CalibrationSettings s;
  s.tangential = true;
  const auto res = recon::calibrate_stereo(views, test::recon_board(), s);
  ASSERT_TRUE(res.ok) << res.message;
  const double want[4] = {0.003, -0.002, 0.0, 0.0};
  const char* names[4] = {"left.p1", "left.p2", "right.p1", "right.p2"};
  for (int i = 0; i < 4; ++i) {
    const auto* p = res.find(names[i]);
    EXPECT_FALSE(p->fixed);
    EXPECT_GT(p->sigma, 0.0);
    EXPECT_LT(p->sigma, 1e-3) << names[i];
    EXPECT_LE(std::abs(p->value - want[i]), 3 * p->sigma) << names[i];
  }
}

TEST(CalibrateOptions, OneEyedViewsAreUsedAndEmptyViewsSkipped) {
  const auto& rig = test::paper_d3();
  auto views = test::noisy_views(rig, test::sample_poses(rig, 10, 41), 0.1, 42);
  views[2].right.clear();   // the left eye only
  views[5].left.clear();    // the right eye only
  views[7].left.resize(3);  // too few corners in both eyes: skipped
  views[7].right.clear();
  const auto res = recon::calibrate_stereo(views, test::recon_board(), {});
  ASSERT_TRUE(res.ok) << res.message;
  ASSERT_EQ(res.skipped_views, std::vector<int>{7});
  ASSERT_EQ(res.views.size(), 9u);
  EXPECT_EQ(res.views[2].right_corners, 0);
  EXPECT_EQ(res.views[2].rms_right_px, 0.0);
  EXPECT_EQ(res.views[5].view, 5);
  EXPECT_EQ(res.views[5].left_corners, 0);
  EXPECT_GT(res.views[5].rms_right_px, 0.0);
  EXPECT_NEAR(res.sigma_px, 0.1, 0.015);
}

TEST(CalibrateOptions, RefusesTooFewViewsAndNoStereo) {
  const auto& rig = test::paper_d3();
  auto views = test::noisy_views(rig, test::sample_poses(rig, 4, 51), 0.1, 52);
  {
    std::vector<recon::CalibrationView> two(views.begin(), views.begin() + 2);
    const auto res = recon::calibrate_stereo(two, test::recon_board(), {});
    EXPECT_FALSE(res.ok);
    EXPECT_NE(res.message.find("at least 3"), std::string::npos) << res.message;
  }
  {
    // Each view seen by one eye only: nothing ties the two cameras together.
    std::vector<recon::CalibrationView> split;
    for (int copy = 0; copy < 2; ++copy)
      for (std::size_t i = 0; i < views.size(); ++i) {
        split.push_back(views[i]);
        (i % 2 ? split.back().left : split.back().right).clear();
      }
    const auto res = recon::calibrate_stereo(split, test::recon_board(), {});
    EXPECT_FALSE(res.ok);
    EXPECT_NE(res.message.find("both eyes"), std::string::npos) << res.message;
  }
  {
    auto bad = views;
    bad[1].left[3].row = 6;  // a 6 x 8 board has rows 0..5
    const auto res = recon::calibrate_stereo(bad, test::recon_board(), {});
    EXPECT_FALSE(res.ok);
    EXPECT_NE(res.message.find("view 1: corner (6, "), std::string::npos) << res.message;
  }
  const auto empty = recon::calibrate_stereo(std::vector<recon::CalibrationView>{}, test::recon_board(), {});
  EXPECT_FALSE(empty.ok);
}

TEST(CalibrateOptions, YamlRoundTripKeepsSigmas) {
  const auto& rig = test::paper_d3();
  const auto views = test::noisy_views(rig, test::sample_poses(rig, 8, 61), 0.1, 62);
  const auto res = recon::calibrate_stereo(views, test::recon_board(), {});
  ASSERT_TRUE(res.ok) << res.message;
  const auto path =
      std::filesystem::temp_directory_path() / ("naneye-calib-" + std::to_string(::getpid()) + ".yaml");
  recon::save_rig(res.rig, path);
  const recon::StereoRig back = recon::load_rig(path);
  std::filesystem::remove(path);
  // FileStorage writes doubles with 16 significant digits.
  EXPECT_TRUE(back.left.K().isApprox(res.rig.left.K(), 1e-14));
  EXPECT_NEAR(back.right.distortion().k3, res.rig.right.distortion().k3, 1e-14);
  EXPECT_TRUE(back.R.isApprox(res.rig.R, 1e-14));
  EXPECT_TRUE(back.T.isApprox(res.rig.T, 1e-14));
  ASSERT_TRUE(back.sigmas.M1 && back.sigmas.M2 && back.sigmas.D1 && back.sigmas.D2 && back.sigmas.om &&
              back.sigmas.T);
  EXPECT_TRUE(back.sigmas.M1->isApprox(*res.rig.sigmas.M1, 1e-14));
  EXPECT_TRUE(back.sigmas.D2->isApprox(*res.rig.sigmas.D2, 1e-14));
  EXPECT_TRUE(back.sigmas.om->isApprox(*res.rig.sigmas.om, 1e-14));
  EXPECT_TRUE(back.sigmas.T->isApprox(*res.rig.sigmas.T, 1e-14));
  EXPECT_GT((*back.sigmas.M1)(0, 0), 0.0);
}

TEST(CalibrateCrossValidation, PaperSplitsAndOddEven) {
  const auto& rig = test::paper_d3();
  const auto views = test::noisy_views(rig, test::sample_poses(rig, 19, 71), 0.1, 72);
  const auto splits = recon::cross_validate_splits(views, test::recon_board(), {}, 3, 10);
  ASSERT_EQ(splits.splits.size(), 3u);
  for (const auto& s : splits.splits) {
    ASSERT_TRUE(s.ok) << s.message;
    EXPECT_EQ(s.train.size(), 10u);
    EXPECT_EQ(s.test.size(), 9u);
    for (int t : s.test) EXPECT_EQ(std::count(s.train.begin(), s.train.end(), t), 0);
    std::printf("split: calib RMS %.4f px, P %.4f mm, D %.4f mm, R %.4f px\n", s.calibration_rms_px,
                s.planarity_mm, s.distance_mm, s.reprojection_px);
    // Corners at 0.1 px triangulated over a ~1 mm baseline at ~70 mm: a depth sigma per corner of
    // Z^2 / (f B) sqrt(2) 0.1 px ~ 3 mm (paper Eq. 2), so a mean |distance| to the plane of ~0.8 of
    // that; D likewise. R is below the corner noise: triangulation absorbs part of it.
    EXPECT_GT(s.planarity_mm, 1.0);
    EXPECT_LT(s.planarity_mm, 4.0);
    EXPECT_GT(s.distance_mm, 0.5);
    EXPECT_LT(s.distance_mm, 4.0);
    EXPECT_LT(s.reprojection_px, 0.15);
    EXPECT_GT(s.reprojection_px, 0.01);
  }
  EXPECT_NE(splits.splits[0].train, splits.splits[1].train);

  const auto oe = recon::cross_validate_odd_even(views, test::recon_board(), {});
  ASSERT_TRUE(oe.ok) << oe.message;
  EXPECT_EQ(oe.odd.used_views.size(), 9u);
  EXPECT_EQ(oe.even.used_views.size(), 10u);
  int beyond3 = 0, free = 0;
  for (const auto& c : oe.parameters) {
    if (c.fixed) continue;
    ++free;
    beyond3 += c.ratio > 3;
    EXPECT_NEAR(c.combined_sigma, std::hypot(c.odd_sigma, c.even_sigma), 1e-15);
  }
  EXPECT_EQ(free, 20);
  std::printf("odd/even: RMS of |difference| / combined sigma = %.3f over %d parameters\n", oe.ratio_rms,
              free);
  // Honest sigmas: the ratios are |N(0, 1)|-like, RMS about 1 (loose: 20 correlated samples).
  EXPECT_GT(oe.ratio_rms, 0.4);
  EXPECT_LT(oe.ratio_rms, 1.8);
  EXPECT_LE(beyond3, 1);
  // The same on depths (every corner both eyes saw, triangulated with each half): one pair of
  // calibrations, so one draw of a shared error: loose bounds, like the parameters'.
  std::printf(
      "odd/even depths: %d corners, median |difference| %.3f %% of Z, median combined sigma %.3f %%, "
      "RMS of the ratios %.2f (marginals taken as independent: %.2f)\n",
      oe.depth_corners, 100 * oe.depth_median_relative, 100 * oe.depth_sigma_median_relative,
      oe.depth_ratio_rms, oe.depth_ratio_rms_independent);
  std::printf("over %zu halvings:", oe.split_depth_ratio_rms.size());
  for (double r : oe.split_depth_ratio_rms) std::printf(" %.2f", r);
  std::printf(", pooled %.2f over %d corners: sigma scale %.2f\n", oe.pooled_depth_ratio_rms,
              oe.pooled_depth_corners, oe.sigma_scale);
  // White 0.1 px noise, honest sigmas: measured 1.30 / 0.91 / 0.64, pooled 0.99, nothing widened.
  EXPECT_EQ(oe.split_depth_ratio_rms.size(), 3u);
  EXPECT_EQ(oe.sigma_scale, 1.0);
  EXPECT_GT(oe.depth_corners, 19 * 40);
  EXPECT_GT(oe.depth_ratio_rms, 0.2);
  EXPECT_LT(oe.depth_ratio_rms, 2.5);
  EXPECT_GT(oe.depth_sigma_median_relative, 0.0);
}
