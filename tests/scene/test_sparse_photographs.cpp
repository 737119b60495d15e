// The sparse scene path on real stereo photographs nobody here made: OpenCV's sample stereo set
// (Debian's opencv-doc, 640 x 480 JPEG, a 9 x 6 inner-corner board of 25 mm squares at 0.2-0.45 m,
// an 84 mm baseline), calibrated in the test as an OpenCV user would (stereoCalibrate on
// cornerSubPix corners). The truth is the board's plane through its 54 corners triangulated in
// both eyes. The board is a periodic pattern, where a guessed match lands a period off: the points
// given must be few but right (at most 5 % more than 5 % off the plane, a tenth of the OpenCV
// path's share: GFTT + pyramidal LK + undistortPoints + triangulatePoints, same calibration, same
// run; the median within 1 %). rms(dZ / sigma) is printed, not held: the sigmas are the match's
// alone, and here the rig's calibration error (a reprojection RMS of ~0.2-0.4 px on this set, far
// above the matches' ~0.07 px) dominates the depth error.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <string>
#include <vector>

#include "../support/photo_frame.hpp"
#include "naneye/recon/geometry/triangulation.hpp"
#include "naneye/recon/scene/sparse.hpp"

namespace naneye::recon::scene {
namespace photographs {

const std::string kDir = "/usr/share/doc/opencv-doc/examples/data";
const cv::Size kBoard(9, 6);
constexpr double kSquareMm = 25.0;

struct View {
  cv::Mat left, right;  // 8-bit grey
  std::vector<cv::Point2f> cl, cr;
};

std::vector<cv::Point2f> corners(const cv::Mat& g, bool& ok) {
  std::vector<cv::Point2f> p;
  ok = cv::findChessboardCorners(g, kBoard, p, cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
  if (ok)
    cv::cornerSubPix(g, p, cv::Size(11, 11), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 30, 0.01));
  return p;
}

std::vector<View> load_views() {
  std::vector<View> views;
  for (int k = 1; k <= 14; ++k) {
    char l[160], r[160];
    std::snprintf(l, sizeof l, "%s/left%02d.jpg", kDir.c_str(), k);
    std::snprintf(r, sizeof r, "%s/right%02d.jpg", kDir.c_str(), k);
    if (!std::filesystem::exists(l) || !std::filesystem::exists(r)) continue;  // the set has no pair 10
    View v{cv::imread(l, cv::IMREAD_GRAYSCALE), cv::imread(r, cv::IMREAD_GRAYSCALE), {}, {}};
    bool okl = false, okr = false;
    v.cl = corners(v.left, okl);
    v.cr = corners(v.right, okr);
    if (okl && okr) views.push_back(std::move(v));
  }
  return views;
}

CameraModel to_model(const cv::Mat& K, const cv::Mat& D, cv::Size size) {
  Eigen::Matrix3d k;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) k(r, c) = K.at<double>(r, c);
  const Distortion d{D.at<double>(0), D.at<double>(1), D.at<double>(2), D.at<double>(3), D.at<double>(4)};
  return CameraModel(k, d, size.width, size.height);
}

// OpenCV's stereo calibration of the set (each eye first, then the pair with the intrinsics fixed).
StereoRig calibrate(const std::vector<View>& views, cv::Mat K[2], cv::Mat D[2], cv::Mat& R, cv::Mat& T) {
  std::vector<std::vector<cv::Point3f>> object(views.size());
  std::vector<std::vector<cv::Point2f>> il, ir;
  for (std::size_t i = 0; i < views.size(); ++i) {
    for (int r = 0; r < kBoard.height; ++r)
      for (int c = 0; c < kBoard.width; ++c)
        object[i].emplace_back(static_cast<float>(kSquareMm * c), static_cast<float>(kSquareMm * r), 0.f);
    il.push_back(views[i].cl);
    ir.push_back(views[i].cr);
  }
  const cv::Size size = views[0].left.size();
  std::vector<cv::Mat> rv, tv;
  cv::calibrateCamera(object, il, size, K[0], D[0], rv, tv);
  cv::calibrateCamera(object, ir, size, K[1], D[1], rv, tv);
  cv::Mat E, F;
  cv::stereoCalibrate(object, il, ir, K[0], D[0], K[1], D[1], size, R, T, E, F, cv::CALIB_FIX_INTRINSIC);
  StereoRig rig{to_model(K[0], D[0], size),
                to_model(K[1], D[1], size),
                Eigen::Matrix3d::Identity(),
                Eigen::Vector3d::Zero(),
                {}};
  for (int r = 0; r < 3; ++r) {
    rig.T(r) = T.at<double>(r);
    for (int c = 0; c < 3; ++c) rig.R(r, c) = R.at<double>(r, c);
  }
  return rig;
}

// The board's plane in the left frame (n . X = d, |n| = 1) from its corners triangulated.
struct Plane {
  Eigen::Vector3d n;
  double d = 0;
  // Depth along the left pixel's ray where it meets the plane.
  double depth_at(const CameraModel& cam, const Eigen::Vector2d& px) const {
    const Eigen::Vector2d x = cam.undistort(px).normalized;
    const Eigen::Vector3d ray(x.x(), x.y(), 1.0);
    return d / n.dot(ray);
  }
};

Plane board_plane(const StereoRig& rig, const View& v) {
  std::vector<Eigen::Vector3d> X;
  for (std::size_t j = 0; j < v.cl.size(); ++j) {
    const Triangulated t =
        triangulate(rig, Eigen::Vector2d(v.cl[j].x, v.cl[j].y), Eigen::Vector2d(v.cr[j].x, v.cr[j].y),
                    TriangulationMethod::refined, 0.1);
    if (t.ok()) X.push_back(t.X);
  }
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& x : X) c += x;
  c /= static_cast<double>(X.size());
  Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
  for (const auto& x : X) S += (x - c) * (x - c).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(S);
  Plane p{es.eigenvectors().col(0), 0};
  p.d = p.n.dot(c);
  return p;
}

// Inside the hull of the board's corners, shrunk by a tenth towards its centre (a point on the
// hull's edge may be the board's or what lies beside it).
bool on_board(const std::vector<cv::Point2f>& corners, const cv::Point2f& p) {
  std::vector<cv::Point2f> hull;
  cv::convexHull(corners, hull);
  cv::Point2f c(0, 0);
  for (const auto& h : hull) c += h;
  c *= 1.0f / static_cast<float>(hull.size());
  for (auto& h : hull) h = c + 0.9f * (h - c);
  return cv::pointPolygonTest(hull, p, false) > 0;
}

struct Tally {
  std::vector<double> rel;  // |dZ| / Z of each point on the board
  double sum_z2 = 0;        // (dZ / sigma)^2 where a sigma is given
  int sigmas = 0;
  void add(double z, double z_true, double sigma) {
    rel.push_back(std::abs(z - z_true) / z_true);
    if (sigma > 0) {
      sum_z2 += (z - z_true) * (z - z_true) / (sigma * sigma);
      ++sigmas;
    }
  }
  int points() const { return static_cast<int>(rel.size()); }
  int off(double share) const {
    return static_cast<int>(std::count_if(rel.begin(), rel.end(), [share](double r) { return r > share; }));
  }
  double median() const {
    std::vector<double> v = rel;
    if (v.empty()) return 0;
    std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
    return v[v.size() / 2];
  }
  void print(const char* name) const {
    std::printf("%-34s %5d points on the board, %4d (%5.2f %%) > 5 %% off its plane, median |dZ|/Z %.3f %%\n",
                name, points(), off(0.05), 100.0 * off(0.05) / std::max(1, points()), 100 * median());
  }
};

TEST(SparsePhotographs, OpenCvStereoSetGivesFewButRightPointsOnTheBoard) {
  if (!std::filesystem::exists(kDir + "/left01.jpg"))
    GTEST_SKIP() << "opencv-doc is not installed (scripts/install-deps.sh installs it)";
  const std::vector<View> views = load_views();
  ASSERT_GE(views.size(), 10u);
  cv::Mat K[2], D[2], R, T;
  const StereoRig rig = calibrate(views, K, D, R, T);
  SparseSettings s;
  s.z_min_mm = 150;  // the set's board lies at ~250-600 mm
  s.z_max_mm = 1500;
  SparseReconstructor sparse(rig, s);
  SparseResult res;
  Tally ours, cv_path;
  const cv::Mat P1 = K[0] * cv::Mat::eye(3, 4, CV_64F);
  cv::Mat Rt;
  cv::hconcat(R, T, Rt);
  const cv::Mat P2 = K[1] * Rt;
  std::vector<int> statuses(8, 0);
  double z_lo = 1e9, z_hi = 0;
  for (const View& v : views) {
    const Plane plane = board_plane(rig, v);
    for (const auto& c : v.cl) {
      const double z = plane.depth_at(rig.left, Eigen::Vector2d(c.x, c.y));
      z_lo = std::min(z_lo, z);
      z_hi = std::max(z_hi, z);
    }
    const test::PhotoFrame l = test::photo_frame(v.left), r = test::photo_frame(v.right);
    sparse.reconstruct(l.view(), r.view(), res);
    for (const ScenePoint& p : res.points) {
      ++statuses[static_cast<std::size_t>(p.status)];
      if (!p.valid() || !on_board(v.cl, cv::Point2f(float(p.left_px.x()), float(p.left_px.y())))) continue;
      ours.add(p.X.z(), plane.depth_at(rig.left, p.left_px), p.depth_sigma_mm);
    }
    // The OpenCV path: GFTT, pyramidal LK from the same place, undistort, triangulate.
    std::vector<cv::Point2f> f0, f1;
    cv::goodFeaturesToTrack(v.left, f0, 1000, 0.01, 5);
    std::vector<uchar> st;
    std::vector<float> err;
    // Four pyramid levels, not the default three: the set's disparities reach ~180 px, beyond what
    // 21 x 21 windows from zero reach with three (the NanEye's 2-25 px need none).
    cv::calcOpticalFlowPyrLK(v.left, v.right, f0, f1, st, err, cv::Size(21, 21), 4);
    std::vector<cv::Point2f> a, b;
    for (std::size_t i = 0; i < f0.size(); ++i)
      if (st[i] && on_board(v.cl, f0[i])) {
        a.push_back(f0[i]);
        b.push_back(f1[i]);
      }
    if (a.empty()) continue;
    std::vector<cv::Point2f> ua, ub;
    cv::undistortPoints(a, ua, K[0], D[0], cv::noArray(), K[0]);
    cv::undistortPoints(b, ub, K[1], D[1], cv::noArray(), K[1]);
    cv::Mat X4;
    cv::triangulatePoints(P1, P2, ua, ub, X4);
    X4.convertTo(X4, CV_64F);
    for (int i = 0; i < X4.cols; ++i) {
      const double z = X4.at<double>(2, i) / X4.at<double>(3, i);
      cv_path.add(z,
                  plane.depth_at(rig.left, Eigen::Vector2d(a[static_cast<std::size_t>(i)].x,
                                                           a[static_cast<std::size_t>(i)].y)),
                  0);
    }
  }
  const double rms = std::sqrt(ours.sum_z2 / std::max(1, ours.sigmas));
  std::printf("%zu pairs, rig baseline %.1f mm, board at %.0f-%.0f mm\n", views.size(), rig.baseline_mm(),
              z_lo, z_hi);
  ours.print("ours (sparse)");
  std::printf("  by status:");
  for (std::size_t k = 0; k < statuses.size(); ++k)
    if (statuses[k] > 0) std::printf(" %s %d", to_string(static_cast<PointStatus>(k)), statuses[k]);
  std::printf("\n  rms(dZ / sigma) %.1f: the sigmas are the match's alone, not the calibration's\n", rms);
  cv_path.print("OpenCV (GFTT + pyramidal LK, 4 lv)");
  // 2026-12-05: ours 54 points, 1 off (a match one checker period off at ZNCC 0.98, beside the true
  // one at 0.96: at this 84 mm baseline the board's foreshortening shears the 7 x 7 coarse windows,
  // which the NanEye's 1 mm never does), median 0.27 %; OpenCV 1 045 points, 99.8 % off. 2026-12-06,
  // the LK sampling the B-spline: 50 points, none off, median 0.25 %, rms(dZ / sigma) 3.1.
  EXPECT_GE(ours.points(), 40);
  EXPECT_LE(20 * ours.off(0.05), ours.points());  // <= 5 %
  EXPECT_LE(10 * ours.off(0.05) * cv_path.points(),
            cv_path.off(0.05) * ours.points());  // <= a tenth of OpenCV's share
  EXPECT_LT(ours.median(), 0.01);
}

}  // namespace photographs
}  // namespace naneye::recon::scene
