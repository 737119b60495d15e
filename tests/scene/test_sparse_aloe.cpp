// The sparse path (recon/scene/sparse.hpp) on a real stereo pair with ground truth: Middlebury's
// Aloe (aloe_data.hpp) at a quarter size, a 250 x 250 crop. Ours runs through
// a pinhole rig (no distortion, R = I, T = (-1 mm, 0, 0), f = 200 px: disparity = 200 / Z), so its
// epipolar curves are the image rows and its matches' disparities compare with the truth directly.
// Beside it, in the same run, the OpenCV path a user would glue (goodFeaturesToTrack +
// calcOpticalFlowPyrLK left -> right, as bench_scene runs it). Neither was tuned on this photograph.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <vector>

#include "../support/photo_frame.hpp"
#include "aloe_data.hpp"
#include "naneye/recon/scene/sparse.hpp"

namespace naneye {
namespace {

constexpr int kSide = 250;      // px; the NanEye's frame, which the sparse path is built for
constexpr double kFocal = 200;  // px; the pinhole rig's (any value: disparity = kFocal * 1 mm / Z)
// px; the right part of the quarter-size view (320 px wide): its matches lie inside the right crop.
constexpr int kCropX = 320 - kSide;

struct AloeCrop {
  cv::Mat l8, r8, gt;         // 8-bit views and the left view's disparity (px, 0 = unknown)
  test::PhotoFrame l16, r16;  // as 10-bit frames: the path's thresholds are in DN of one
};

AloeCrop load_crop() {
  AloeCrop a;
  const test::AloeQuarter q = test::load_aloe_quarter();
  if (q.l.empty()) return a;
  const cv::Rect roi(kCropX, 0, kSide, kSide);
  a.l8 = q.l(roi).clone();
  a.r8 = q.r(roi).clone();
  a.gt = q.gt(roi).clone();
  a.l16 = test::photo_frame(a.l8);
  a.r16 = test::photo_frame(a.r8);
  return a;
}

recon::StereoRig pinhole_rig() {
  Eigen::Matrix3d K;
  K << kFocal, 0, (kSide - 1) / 2.0, 0, kFocal, (kSide - 1) / 2.0, 0, 0, 1;
  recon::StereoRig rig;
  rig.left = recon::CameraModel(K, recon::Distortion{}, kSide, kSide);
  rig.right = rig.left;
  rig.T = Eigen::Vector3d(-1, 0, 0);
  return rig;
}

struct Tally {
  int given = 0, known = 0, bad1 = 0, bad05 = 0;
  double abs_sum = 0;
  void add(double u, double v, double disparity, const cv::Mat& gt) {
    ++given;
    const float g = gt.at<float>(static_cast<int>(std::lround(v)), static_cast<int>(std::lround(u)));
    if (!(g > 0)) return;  // occluded or unknown in the truth: not scored
    ++known;
    const double e = std::abs(disparity - g);
    bad1 += e > 1.0;
    bad05 += e > 0.5;
    abs_sum += std::min(e, 1.0);
  }
  double bad1_share() const { return static_cast<double>(bad1) / std::max(1, known); }
  void print(const char* who) const {
    std::printf(
        "%-28s points %4d scored %4d  bad-1.0 %5.2f %%  bad-0.5 %5.2f %%  mean |err| (capped 1 px) %.3f px\n",
        who, given, known, 100.0 * bad1 / std::max(1, known), 100.0 * bad05 / std::max(1, known),
        abs_sum / std::max(1, known));
  }
};

Tally ours(const AloeCrop& a, const recon::scene::SparseSettings& s) {
  const recon::StereoRig rig = pinhole_rig();
  recon::scene::SparseReconstructor sr(rig, s);
  recon::scene::SparseResult res;
  sr.reconstruct(a.l16.view(), a.r16.view(), res);
  Tally t;
  for (const auto& p : res.points)
    if (p.valid()) t.add(p.left_px.x(), p.left_px.y(), p.left_px.x() - p.right_px.x(), a.gt);
  return t;
}

Tally opencv(const AloeCrop& a) {
  std::vector<cv::Point2f> pl, pr;
  cv::goodFeaturesToTrack(a.l8, pl, 500, 0.01, 5);
  std::vector<unsigned char> status;
  std::vector<float> err;
  if (!pl.empty()) cv::calcOpticalFlowPyrLK(a.l8, a.r8, pl, pr, status, err, cv::Size(21, 21), 3);
  Tally t;
  for (std::size_t i = 0; i < pl.size(); ++i)
    if (status[i]) t.add(pl[i].x, pl[i].y, pl[i].x - pr[i].x, a.gt);
  return t;
}

TEST(SparseAloe, MatchesARealPhotographAndBeatsTheOpenCvPath) {
  if (!std::filesystem::exists(test::kAloeDir / "aloeGT.png")) GTEST_SKIP() << "opencv-doc is not installed";
  const AloeCrop a = load_crop();
  ASSERT_FALSE(a.l16.dn.empty());
  double gmin = 1e9, gmax = 0;
  for (int y = 0; y < kSide; ++y)
    for (int x = 0; x < kSide; ++x)
      if (const float g = a.gt.at<float>(y, x); g > 0) {
        gmin = std::min<double>(gmin, g);
        gmax = std::max<double>(gmax, g);
      }
  recon::scene::SparseSettings s;
  s.z_min_mm = kFocal / (gmax + 2);  // the truth's disparities, 2 px to spare each way
  s.z_max_mm = kFocal / std::max(1.0, gmin - 2);
  const Tally mine = ours(a, s);
  recon::scene::SparseSettings raw = s;  // the search on raw pixels, the fixed final ZNCC alone
  raw.search_binomial = false;
  raw.final_noise_false_reject = 0;
  const Tally before = ours(a, raw);
  const Tally cv_path = opencv(a);
  std::printf("Aloe, quarter size, 250 x 250 crop, disparities %.1f-%.1f px\n", gmin, gmax);
  mine.print("ours");
  before.print("ours, raw search, ZNCC 0.9");
  cv_path.print("OpenCV (GFTT + pyramidal LK)");
  EXPECT_GE(mine.known, 300);
  // A real photograph has occlusion edges and a JPEG's blocks: wrong matches (> 1 px off) stay rare
  // and at most a fifth of the OpenCV path's share.
  EXPECT_LE(mine.bad1_share(), 0.02);
  EXPECT_LE(mine.bad1_share(), cv_path.bad1_share() / 5);
  // The faint-texture rules (filtered search, noise-residual acceptance) must not buy their points
  // with wrong ones here: at most one wrong point more than the raw search's share allows.
  EXPECT_LE(mine.bad1, before.bad1_share() * mine.known + 1);
}

}  // namespace
}  // namespace naneye
