// The rectified matcher (recon/scene/dense_match.hpp) on a real stereo pair with ground truth:
// Middlebury's Aloe (aloe_data.hpp), against cv::StereoSGBM over the same disparity band.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "aloe_data.hpp"
#include "naneye/recon/scene/dense_match.hpp"

namespace naneye {
namespace {

struct Bad {
  int known = 0, given = 0, bad_given = 0;
  double all() const { return static_cast<double>(bad_given + (known - given)) / std::max(1, known); }
  double of_given() const { return static_cast<double>(bad_given) / std::max(1, given); }
  double coverage() const { return static_cast<double>(given) / std::max(1, known); }
};

// bad-t: share of the pixels with a known disparity whose disparity is off by more than t px;
// all() counts a pixel without disparity as bad (Middlebury's convention), of_given() only the given.
Bad bad_pixels(const cv::Mat& disp, const cv::Mat& gt, double t) {
  Bad b;
  for (int r = 0; r < gt.rows; ++r)
    for (int c = 0; c < gt.cols; ++c) {
      const float g = gt.at<float>(r, c);
      if (!(g > 0)) continue;
      ++b.known;
      const float d = disp.at<float>(r, c);
      if (!std::isfinite(d)) continue;
      ++b.given;
      b.bad_given += std::abs(d - g) > t;
    }
  return b;
}

// Aloe at a quarter of the size (keeps the tests short; the disparities scale with it): the 8-bit
// views for SGBM, their float copies for ours, the truth, and the band that holds it.
struct Aloe {
  cv::Mat l, r, lf, rf, g;
  int band = 0;
};

Aloe load_aloe() {
  Aloe a;
  const test::AloeQuarter q = test::load_aloe_quarter();
  if (q.l.empty()) return a;
  a.l = q.l;
  a.r = q.r;
  a.g = q.gt;
  double gmax = 0;
  cv::minMaxLoc(a.g, nullptr, &gmax);
  a.band = (static_cast<int>(std::ceil(gmax)) + 2 + 15) / 16 * 16;
  a.l.convertTo(a.lf, CV_32F);
  a.r.convertTo(a.rf, CV_32F);
  return a;
}

TEST(DenseAloe, MatcherNoWorseThanSgbm) {
  if (!std::filesystem::exists(test::kAloeDir / "aloeGT.png")) GTEST_SKIP() << "opencv-doc is not installed";
  const Aloe a = load_aloe();
  ASSERT_FALSE(a.l.empty() || a.r.empty() || a.g.empty());
  const cv::Mat &l = a.l, &r = a.r, &lf = a.lf, &rf = a.rf, &g = a.g;
  const int band = a.band;
  const cv::Mat valid(l.rows, l.cols, CV_8UC1, cv::Scalar(1));

  recon::scene::MatcherSettings ms;
  ms.min_disparity = 0;
  ms.num_disparities = band;
  recon::scene::RectifiedMatcher matcher(l.cols, l.rows, ms);
  matcher.match(lf, rf, valid, valid);

  // OpenCV as its users run it: the parameters its documentation and samples give (block 5,
  // P1 = 8 * 5^2, P2 = 32 * 5^2, uniqueness 10, speckle window 100 / range 32, left-right 1 px).
  auto sgbm =
      cv::StereoSGBM::create(0, band, 5, 8 * 25, 32 * 25, 1, 0, 10, 100, 32, cv::StereoSGBM::MODE_SGBM);
  cv::Mat d16, dcv(l.rows, l.cols, CV_32FC1);
  sgbm->compute(l, r, d16);
  for (int y = 0; y < l.rows; ++y)
    for (int x = 0; x < l.cols; ++x) {
      const short v = d16.at<short>(y, x);
      dcv.at<float>(y, x) = v < 0 ? NAN : v / 16.f;
    }
  const auto& k = matcher.counts();
  std::printf(
      "ours: candidates %d, refused: no integer %d, window %d, shift %d, texture %d, not converged %d, "
      "residual %d, left-right %d, occluded %d; valid %d; window radius %d\n",
      k.candidates, k.no_integer, k.window, k.shift, k.texture, k.converged, k.residual, k.left_right,
      k.occluded, k.valid, matcher.radius_used());
  // A real photo, sharp: the sigma bound refuses 6.3 % of the candidates, below grow_share.
  EXPECT_EQ(matcher.radius_used(), 3);
  for (double t : {0.5, 1.0, 2.0}) {
    const Bad ours = bad_pixels(matcher.disparity(), g, t), cv_ = bad_pixels(dcv, g, t);
    std::printf(
        "Aloe %dx%d band %d  bad-%.1f: ours %.2f %% of given (coverage %.1f %%, %.2f %% counting none as "
        "bad)  "
        "SGBM %.2f %% of given (coverage %.1f %%, %.2f %%)\n",
        l.cols, l.rows, band, t, 100 * ours.of_given(), 100 * ours.coverage(), 100 * ours.all(),
        100 * cv_.of_given(), 100 * cv_.coverage(), 100 * cv_.all());
    if (t == 2.0) {
      EXPECT_LE(ours.of_given(), cv_.of_given());
      // Ours refuses more than OpenCV's filters do on this real pair (31 % of the known pixels
      // against 72 %: large occlusions, JPEG, unequal exposure; docs/scene.md): held to that, so a
      // lower bad-2.0 is not bought by refusing everything.
      EXPECT_GE(ours.coverage(), 0.3 * cv_.coverage());
    }
  }
}

// The larger window must prove itself on the pair: on Aloe (depth edges everywhere) r = 4 gives
// fewer valid pixels (coverage 42.4 -> 36.2 %, docs/scene.md), so a trial forced on every pair
// (grow_share 0) must lose and leave r = 3's result.
TEST(DenseAloe, LargerWindowTriedLosesOnItsValidCount) {
  if (!std::filesystem::exists(test::kAloeDir / "aloeGT.png")) GTEST_SKIP() << "opencv-doc is not installed";
  const Aloe a = load_aloe();
  ASSERT_FALSE(a.l.empty());
  const cv::Mat valid(a.l.rows, a.l.cols, CV_8UC1, cv::Scalar(1));
  recon::scene::MatcherSettings fixed;
  fixed.num_disparities = a.band;
  fixed.max_radius = fixed.radius;
  recon::scene::MatcherSettings tried = fixed;
  tried.max_radius = 5;
  tried.grow_share = 0;
  recon::scene::RectifiedMatcher m3(a.l.cols, a.l.rows, fixed), m(a.l.cols, a.l.rows, tried);
  m3.match(a.lf, a.rf, valid, valid);
  m.match(a.lf, a.rf, valid, valid);
  EXPECT_EQ(m.radius_used(), 3);
  EXPECT_EQ(m.counts().valid, m3.counts().valid);
  for (int y = 0; y < a.l.rows; ++y)
    for (int x = 0; x < a.l.cols; ++x) {
      const float p = m3.disparity().at<float>(y, x), q = m.disparity().at<float>(y, x);
      ASSERT_TRUE(p == q || (std::isnan(p) && std::isnan(q))) << x << ", " << y;
    }
}

// The matcher works only on the rows' spans of left data and keeps its planes zero outside them
// (dense_match.hpp): one reused on another mask must give what a fresh one gives.
TEST(DenseAloe, MatcherReusedOnAnotherMaskGivesAFreshOnesResult) {
  if (!std::filesystem::exists(test::kAloeDir / "aloeL.jpg")) GTEST_SKIP() << "opencv-doc is not installed";
  const test::AloeQuarter q = test::load_aloe_quarter();
  const cv::Mat &l = q.l, &r = q.r;
  ASSERT_FALSE(l.empty() || r.empty());
  cv::Mat lf, rf;
  l.convertTo(lf, CV_32F);
  r.convertTo(rf, CV_32F);
  const cv::Mat all(l.rows, l.cols, CV_8UC1, cv::Scalar(1));
  cv::Mat disc = cv::Mat::zeros(l.rows, l.cols, CV_8UC1);  // a domain like the NanEye's, off centre
  cv::circle(disc, cv::Point(l.cols / 2 + 20, l.rows / 2), l.rows / 2 - 10, cv::Scalar(1), cv::FILLED);
  recon::scene::MatcherSettings ms;
  ms.num_disparities = 64;
  recon::scene::RectifiedMatcher fresh(l.cols, l.rows, ms), reused(l.cols, l.rows, ms);
  fresh.match(lf, rf, disc, all);
  reused.match(lf, rf, all, all);
  reused.match(lf, rf, disc, all);
  int valid = 0;
  for (int y = 0; y < l.rows; ++y)
    for (int x = 0; x < l.cols; ++x) {
      const float a = fresh.disparity().at<float>(y, x), b = reused.disparity().at<float>(y, x);
      valid += std::isfinite(a);
      ASSERT_TRUE(a == b || (std::isnan(a) && std::isnan(b))) << x << ", " << y;
      const float sa = fresh.sigma().at<float>(y, x), sb = reused.sigma().at<float>(y, x);
      ASSERT_TRUE(sa == sb || (std::isnan(sa) && std::isnan(sb))) << x << ", " << y;
    }
  EXPECT_GT(valid, 10000);
}

}  // namespace
}  // namespace naneye
