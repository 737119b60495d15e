#pragma once
// The OpenCV paths a user would glue together (issue 14), sparse and dense, on bench_scene's renders:
// timed by the thread's CPU clock, tallied against the truth like ours.
#include <Eigen/Core>  // before opencv2/core/eigen.hpp

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <vector>

#include "naneye/recon/pair/opencv_path.hpp"
#include "naneye/recon/scene/sparse.hpp"
#include "scene_tally.hpp"
#include "thread_clock.hpp"

namespace naneye::bench_scene {

using bench::thread_cpu_s;

// The OpenCV path's 8-bit image: the 10-bit scale to 8 bits, the same for both eyes, as a user
// dropping the two low bits gets it. Until 2026-12-06 this stretched each image min-max: the eyes'
// defect pixels (hot 1023, dead 0, stuck 512) set the stretch, so the two eyes differed in scale
// and LK in brightness; that path lost 2-3x the outliers it loses here (docs/scene.md).
cv::Mat to8(const std::vector<float>& luma) {
  const cv::Mat f(250, 250, CV_32FC1, const_cast<float*>(luma.data()));
  cv::Mat out;
  f.convertTo(out, CV_8U, 255.0 / 1023.0);
  return out;
}

void opencv_path(const recon::StereoRig& rig, const recon::scene::StereoLuma& luma, const cv::Mat& truth,
                 Tally& t) {
  const double t0 = thread_cpu_s();
  const cv::Mat l8 = to8(luma.left), r8 = to8(luma.right);
  std::vector<cv::Point2f> pl, pr;
  cv::goodFeaturesToTrack(l8, pl, 500, 0.01, 5);
  std::vector<unsigned char> status;
  std::vector<float> err;
  if (!pl.empty()) cv::calcOpticalFlowPyrLK(l8, r8, pl, pr, status, err, cv::Size(21, 21), 3);
  std::vector<cv::Point2f> gl, gr;
  for (std::size_t i = 0; i < pl.size(); ++i)
    if (status[i]) {
      gl.push_back(pl[i]);
      gr.push_back(pr[i]);
    }
  const auto [K1, D1, K2, D2, R, T] = recon::opencv_rig(rig);
  cv::Mat X;
  if (!gl.empty()) {
    std::vector<cv::Point2f> nl, nr;
    cv::undistortPoints(gl, nl, K1, D1);
    cv::undistortPoints(gr, nr, K2, D2);
    cv::Mat P1 = cv::Mat::eye(3, 4, CV_64F), P2(3, 4, CV_64F);
    R.copyTo(P2.colRange(0, 3));
    T.copyTo(P2.col(3));
    cv::triangulatePoints(P1, P2, nl, nr, X);
    X.convertTo(X, CV_64F);
  }
  t.ms.push_back(1e3 * (thread_cpu_s() - t0));
  ++t.pairs;
  for (std::size_t i = 0; i < gl.size(); ++i) {
    const double w = X.at<double>(3, static_cast<int>(i));
    t.add(X.at<double>(2, static_cast<int>(i)) / w, truth, gl[i].x, gl[i].y);
  }
}

// The OpenCV dense path a user would glue: stereoRectify (alpha 0) + initUndistortRectifyMap +
// remap + StereoSGBM (3-way, block 5, the documented P1 / P2, uniqueness 10, speckle 100 / 32,
// left-right 1 px) + reprojectImageTo3D, read back at each left raw pixel's rectified position
// (undistortPoints with R1, P1: OpenCV's own map, computed once like the rectification maps).
struct OpenCvDense {
  cv::Mat m1x, m1y, m2x, m2y, Q, R1, raw_x, raw_y;
  cv::Mat z;  // the last pair's depth on the left raw grid (NaN: none)
  cv::Ptr<cv::StereoSGBM> sgbm;
  int min_disp = 0, num_disp = 48;
  explicit OpenCvDense(const recon::StereoRig& rig) {
    const auto [K1, D1, K2, D2, R, T] = recon::opencv_rig(rig);
    cv::Mat R2, P1, P2;
    const cv::Size size(rig.left.width(), rig.left.height());
    cv::stereoRectify(K1, D1, K2, D2, size, R, T, R1, R2, P1, P2, Q, cv::CALIB_ZERO_DISPARITY, 0);
    cv::initUndistortRectifyMap(K1, D1, R1, P1, size, CV_32FC1, m1x, m1y);
    cv::initUndistortRectifyMap(K2, D2, R2, P2, size, CV_32FC1, m2x, m2y);
    // The same depth band as ours (5-150 mm): |disparity| = f' B / Z.
    const double fb = P1.at<double>(0, 0) * cv::norm(T);
    min_disp = static_cast<int>(std::floor(fb / 150.0));
    num_disp = (static_cast<int>(std::ceil(fb / 5.0)) - min_disp + 16) / 16 * 16;
    sgbm = cv::StereoSGBM::create(min_disp, num_disp, 5, 8 * 25, 32 * 25, 1, 0, 10, 100, 32,
                                  cv::StereoSGBM::MODE_SGBM_3WAY);
    std::vector<cv::Point2f> px, rect;
    for (int r = 0; r < size.height; ++r)
      for (int c = 0; c < size.width; ++c) px.emplace_back(static_cast<float>(c), static_cast<float>(r));
    cv::undistortPoints(px, rect, K1, D1, R1, P1);
    raw_x.create(size, CV_32FC1);
    raw_y.create(size, CV_32FC1);
    for (int r = 0, k = 0; r < size.height; ++r)
      for (int c = 0; c < size.width; ++c, ++k) {
        raw_x.at<float>(r, c) = rect[static_cast<std::size_t>(k)].x;
        raw_y.at<float>(r, c) = rect[static_cast<std::size_t>(k)].y;
      }
  }
  void run(const recon::scene::StereoLuma& luma, const cv::Mat& truth, DenseTally& t) {
    const double t0 = thread_cpu_s();
    const cv::Mat l8 = to8(luma.left), r8 = to8(luma.right);
    cv::Mat lr, rr, d16, df, xyz;
    cv::remap(l8, lr, m1x, m1y, cv::INTER_LINEAR);
    cv::remap(r8, rr, m2x, m2y, cv::INTER_LINEAR);
    sgbm->compute(lr, rr, d16);
    d16.convertTo(df, CV_32F, 1.0 / 16);
    cv::reprojectImageTo3D(df, xyz, Q, true);
    z.create(truth.rows, truth.cols, CV_32FC1);
    z.setTo(cv::Scalar(NAN));
    const cv::Matx33d Rt = cv::Matx33d(R1).t();
    for (int r = 0; r < z.rows; ++r)
      for (int c = 0; c < z.cols; ++c) {
        const int x = static_cast<int>(std::lround(raw_x.at<float>(r, c)));
        const int y = static_cast<int>(std::lround(raw_y.at<float>(r, c)));
        if (x < 0 || y < 0 || x >= xyz.cols || y >= xyz.rows) continue;
        if (df.at<float>(y, x) < min_disp) continue;  // SGBM's "no disparity"
        const cv::Vec3f p = xyz.at<cv::Vec3f>(y, x);
        if (!std::isfinite(p[2]) || p[2] >= 10000) continue;  // reprojectImageTo3D's missing value
        const cv::Vec3d q = Rt * cv::Vec3d(p[0], p[1], p[2]);
        z.at<float>(r, c) = static_cast<float>(q[2]);
      }
    t.ms.push_back(1e3 * (thread_cpu_s() - t0));
    t.add(z, truth);
  }
};

}  // namespace naneye::bench_scene
