#include "naneye/recon/pair/opencv_path.hpp"

#include <algorithm>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

namespace naneye::recon {
namespace {

// One eye: luminance, 8-bit stretch, findChessboardCorners, cornerSubPix. Empty when not found.
std::vector<cv::Point2f> detect_eye(const RawImageView& image, const OpenCvPathOptions& o) {
  cv::Mat luma(image.height, image.width, CV_32FC1), scratch(image.height, image.width, CV_32FC1);
  raw_to_luminance(image, luma.ptr<float>(), scratch.ptr<float>());
  cv::Mat gray8;
  cv::normalize(luma, gray8, 0, 255, cv::NORM_MINMAX, CV_8U);
  std::vector<cv::Point2f> pts;
  if (!cv::findChessboardCorners(gray8, cv::Size(o.cols, o.rows), pts,
                                 cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE))
    return {};
  cv::cornerSubPix(luma, pts, cv::Size(o.subpix_half_window, o.subpix_half_window), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 30, 0.001));
  return pts;
}

cv::Mat camera_matrix(const CameraModel& c) {
  cv::Mat K;
  cv::eigen2cv(c.K(), K);
  return K;
}

cv::Mat dist_coeffs(const CameraModel& c) {
  const Distortion& d = c.distortion();
  return (cv::Mat_<double>(1, 5) << d.k1, d.k2, d.p1, d.p2, d.k3);
}

}  // namespace

OpenCvPathResult opencv_reconstruct_pair(const StereoRig& rig, const RawImageView& left,
                                         const RawImageView& right, const OpenCvPathOptions& o) {
  OpenCvPathResult res;
  const int n = o.rows * o.cols;
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
    c.rows = o.rows;
    c.cols = o.cols;
    c.count = n;
    for (int i = 0; i < n; ++i) {
      Corner& k = c.corners[static_cast<std::size_t>(i)];
      k.px = {pl[static_cast<std::size_t>(i)].x, pl[static_cast<std::size_t>(i)].y};
      k.row = i / o.cols;
      k.col = i % o.cols;
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

  std::vector<cv::Point2f> nl, nr;
  cv::undistortPoints(pl, nl, camera_matrix(rig.left), dist_coeffs(rig.left));
  cv::undistortPoints(pr, nr, camera_matrix(rig.right), dist_coeffs(rig.right));
  cv::Mat P1 = cv::Mat::eye(3, 4, CV_64F), P2(3, 4, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) P2.at<double>(r, c) = rig.R(r, c);
    P2.at<double>(r, 3) = rig.T(r);
  }
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
