// The dense band from the sparse points (band_around, DenseSettings::band_from_sparse) on a real
// photograph with ground truth, Middlebury's Aloe at a quarter size, where nothing here was rendered:
// the sparse path runs on the 250 x 250 right part (through a pinhole rig, as in
// test_sparse_aloe.cpp), its disparities give the band, and the rectified matcher runs on the whole
// 320-px view with that band and with the whole one. The left 70 columns hold surfaces the points
// never saw.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "../support/photo_frame.hpp"
#include "aloe_data.hpp"
#include "naneye/recon/scene/dense_match.hpp"
#include "naneye/recon/scene/sparse.hpp"

namespace naneye::dense_band_aloe_test {

constexpr int kSide = 250;  // px; the sparse path's frame (the NanEye's)

struct Scored {
  int known = 0, given = 0, bad2 = 0;
};

// bad-2.0 (Middlebury's) of the given disparities in columns [c0, c1).
Scored score(const cv::Mat& disp, const cv::Mat& gt, int c0, int c1) {
  Scored s;
  for (int r = 0; r < gt.rows; ++r)
    for (int c = c0; c < c1; ++c) {
      const float g = gt.at<float>(r, c);
      if (!(g > 0)) continue;
      ++s.known;
      const float d = disp.at<float>(r, c);
      if (!std::isfinite(d)) continue;
      ++s.given;
      s.bad2 += std::abs(d - g) > 2.0f;
    }
  return s;
}

TEST(DenseBandAloe, ABandFromTheSparsePointsOfAPhotograph) {
  if (!std::filesystem::exists(test::kAloeDir / "aloeGT.png")) GTEST_SKIP() << "opencv-doc is not installed";
  const test::AloeQuarter q = test::load_aloe_quarter();
  ASSERT_FALSE(q.l.empty());
  const int crop_x = q.l.cols - kSide;
  const cv::Rect roi(crop_x, 0, kSide, kSide);
  const test::PhotoFrame l16 = test::photo_frame(q.l(roi).clone()), r16 = test::photo_frame(q.r(roi).clone());
  Eigen::Matrix3d K;
  K << 200, 0, (kSide - 1) / 2.0, 0, 200, (kSide - 1) / 2.0, 0, 0, 1;
  recon::StereoRig rig;
  rig.left = recon::CameraModel(K, recon::Distortion{}, kSide, kSide);
  rig.right = rig.left;
  rig.T = Eigen::Vector3d(-1, 0, 0);
  recon::scene::SparseReconstructor sr(rig);
  recon::scene::SparseResult res;
  sr.reconstruct(l16.view(), r16.view(), res);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& p : res.points)
    if (p.valid()) {
      lo = std::min(lo, p.left_px.x() - p.right_px.x());
      hi = std::max(hi, p.left_px.x() - p.right_px.x());
    }
  ASSERT_GE(res.valid_count, recon::scene::DenseSettings{}.min_band_points);

  double gmax = 0;
  cv::minMaxLoc(q.gt, nullptr, &gmax);
  recon::scene::MatcherSettings ms;
  ms.num_disparities = (static_cast<int>(std::ceil(gmax)) + 2 + 15) / 16 * 16 + 16;  // room to narrow
  const recon::scene::DisparityBand whole{0, ms.num_disparities};
  const recon::scene::DisparityBand band =
      recon::scene::band_around(lo, hi, recon::scene::DenseSettings{}.band_margin_px, whole);
  ASSERT_LT(band.num_disparities, whole.num_disparities);

  cv::Mat lf, rf;
  q.l.convertTo(lf, CV_32F);
  q.r.convertTo(rf, CV_32F);
  const cv::Mat valid(q.l.rows, q.l.cols, CV_8UC1, cv::Scalar(1));
  recon::scene::RectifiedMatcher narrowed(q.l.cols, q.l.rows, ms), full(q.l.cols, q.l.rows, ms);
  narrowed.set_band(band.min_disparity, band.num_disparities);
  narrowed.match(lf, rf, valid, valid);
  full.match(lf, rf, valid, valid);
  // The crop's columns far enough right that both bands' first matched column lies left of them.
  const int c0 = crop_x + whole.min_disparity + whole.num_disparities;
  const Scored in_n = score(narrowed.disparity(), q.gt, c0, q.l.cols),
               in_w = score(full.disparity(), q.gt, c0, q.l.cols);
  const Scored out_n = score(narrowed.disparity(), q.gt, 0, crop_x),
               out_w = score(full.disparity(), q.gt, 0, crop_x);
  std::printf(
      "Aloe: %d sparse points, disparities %.2f-%.2f px -> band %d+%d (whole %d+%d)\n"
      "  columns %d-%d (the points' crop): given %d / %d (whole band %d), bad-2.0 %.2f %% (whole %.2f %%)\n"
      "  columns 0-%d (no point there): given %d / %d (whole band %d), bad-2.0 %.2f %% (whole %.2f %%); band "
      "edge refusals %d\n",
      res.valid_count, lo, hi, band.min_disparity, band.num_disparities, whole.min_disparity,
      whole.num_disparities, c0, q.l.cols - 1, in_n.given, in_n.known, in_w.given,
      100.0 * in_n.bad2 / std::max(1, in_n.given), 100.0 * in_w.bad2 / std::max(1, in_w.given), crop_x - 1,
      out_n.given, out_n.known, out_w.given, 100.0 * out_n.bad2 / std::max(1, out_n.given),
      100.0 * out_w.bad2 / std::max(1, out_w.given), narrowed.counts().band_edge);
  // What the band trades here (why DenseSettings::band_from_sparse is off by default): in the crop
  // more pixels (measured 22 998 against 20 589) at a higher bad-2.0 (1.22 % against 0.81 %: the
  // left-right check is weaker in a narrower band, and background pixels beside a nearer object's
  // edge take its disparity); held to that, so that a change either way shows. Where no point
  // was, the whole band matched nothing (its first column lies right of them) and the band gives
  // few wrong ones (0.10 %).
  EXPECT_GE(in_n.given, in_w.given);
  EXPECT_LE(in_n.bad2, 0.015 * in_n.given);
  EXPECT_LE(out_n.bad2, 0.005 * std::max(1, out_n.given));
}

}  // namespace naneye::dense_band_aloe_test
