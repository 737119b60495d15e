#include "naneye/recon/pair/opencv_path.hpp"

#include <algorithm>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

namespace naneye::recon {
namespace {

// One eye: luminance, 8-bit stretch, findChessboardCorners, cornerSubPix. Empty when not found.
std::vector<cv::Point2f> detect_eye(const RawImageView& image, const OpenCvPathSettings& o) {
  cv::Mat luma(image.height, image.width, CV_32FC1), scratch(image.height, image.width, CV_32FC1);
  raw_to_luminance(image, luma.ptr<float>(), scratch.ptr<float>());
  cv::Mat gray8;
  cv::normalize(luma, gray8, 0, 255, cv::NORM_MINMAX, CV_8U);
  std::vector<cv::Point2f> pts;
  if (!cv::findChessboardCorners(gray8, cv::Size(o.board.cols, o.board.rows), pts,
                                 cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE))
    return {};
  cv::cornerSubPix(luma, pts, cv::Size(o.subpix_half_window, o.subpix_half_window), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 30, 0.001));
  return pts;
}

}  // namespace

OpenCvRig opencv_rig(const StereoRig& rig) {
  OpenCvRig o;
  cv::eigen2cv(rig.left.K(), o.K1);
  cv::eigen2cv(rig.right.K(), o.K2);
  cv::eigen2cv(rig.left.distortion().opencv_order(), o.D1);
  cv::eigen2cv(rig.right.distortion().opencv_order(), o.D2);
  cv::eigen2cv(rig.R, o.R);
  cv::eigen2cv(rig.T, o.T);
  return o;
}

OpenCvPathResult opencv_reconstruct_pair(const StereoRig& rig, const RawImageView& left,
                                         const RawImageView& right, const OpenCvPathSettings& o) {
  OpenCvPathResult res;
  const int n = o.board.rows * o.board.cols;
  std::vector<cv::Point2f> pl = detect_eye(left, o);
  if (static_cast<int>(pl.size()) != n) return res;
  std::vector<cv::Point2f> pr = detect_eye(right, o);
  if (static_cast<int>(pr.size()) != n) return res;

  // The user's 180-degree check: both grids numbered from the same physical corner.
  const cv::Point2f dl = pl.back() - pl.front(), dr = pr.back() - pr.front();
  if (dl.dot(dr) < 0) std::reverse(pr.begin(), pr.end());
  // Our numbering convention (canonical_order, which may also mirror the rows), decided on the
  // left eye and applied to both; each corner carries its OpenCV index through the reordering.
  if (n <= kMaxCorners) {
    CornerResult c;
    c.found = true;
    c.rows = o.board.rows;
    c.cols = o.board.cols;
    c.count = n;
    for (int i = 0; i < n; ++i) {
      Corner& k = c.corners[static_cast<std::size_t>(i)];
      k.px = {pl[static_cast<std::size_t>(i)].x, pl[static_cast<std::size_t>(i)].y};
      k.row = i / o.board.cols;
      k.col = i % o.board.cols;
      k.contrast = i;
    }
    canonical_order(c);
    const std::vector<cv::Point2f> ol = pl, orr = pr;
    for (int i = 0; i < n; ++i) {
      const auto from = static_cast<std::size_t>(c.corners[static_cast<std::size_t>(i)].contrast);
      pl[static_cast<std::size_t>(i)] = ol[from];
      pr[static_cast<std::size_t>(i)] = orr[from];
    }
  }

  const OpenCvRig cvr = opencv_rig(rig);
  std::vector<cv::Point2f> nl, nr;
  cv::undistortPoints(pl, nl, cvr.K1, cvr.D1);
  cv::undistortPoints(pr, nr, cvr.K2, cvr.D2);
  cv::Mat P1 = cv::Mat::eye(3, 4, CV_64F), P2(3, 4, CV_64F);
  cvr.R.copyTo(P2.colRange(0, 3));
  cvr.T.copyTo(P2.col(3));
  cv::Mat X;  // 4 x n homogeneous
  cv::triangulatePoints(P1, P2, nl, nr, X);
  X.convertTo(X, CV_64F);

  res.found = true;
  res.left_px.reserve(pl.size());
  res.right_px.reserve(pr.size());
  res.xyz_mm.reserve(pl.size());
  for (int i = 0; i < n; ++i) {
    res.left_px.emplace_back(pl[static_cast<std::size_t>(i)]);
    res.right_px.emplace_back(pr[static_cast<std::size_t>(i)]);
    const double w = X.at<double>(3, i);
    res.xyz_mm.emplace_back(X.at<double>(0, i) / w, X.at<double>(1, i) / w, X.at<double>(2, i) / w);
  }
  return res;
}

}  // namespace naneye::recon
