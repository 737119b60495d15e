// Real photographs nobody here rendered: OpenCV's sample stereo set (Debian's opencv-doc, 13 pairs of
// a 9 x 6 inner-corner board, 640 x 480 JPEG, squares ~25-45 px across). Every corner of every board
// found within 0.3 px of OpenCV's cornerSubPix, or, where the two disagree, nearer the board's plane
// than cornerSubPix's (a wrong board is a failure, a missed one is counted).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "../support/photo_frame.hpp"
#include "naneye/recon/corners/detector.hpp"

namespace naneye::recon {
namespace {

const char* const kDir = "/usr/share/doc/opencv-doc/examples/data";
// Where ours and cornerSubPix's disagree by more than the 0.3 px, the board decides: its
// corners are a homography of the board's grid in undistorted coordinates (with OpenCV's lens).
// The plane comes from cornerSubPix's own corners (LMedS, so the ones drawn off a junction do not
// bend it); its prediction at a corner, from 54 corners of ~0.15 px noise, is good to ~0.15 *
// sqrt(8 / 54) = 0.06 px, so ours must be no farther from it than cornerSubPix's plus 0.1 px.
constexpr double kAgreePx = 0.3;
constexpr double kPlaneSlackPx = 0.1;

// OpenCV's own calibration of one eye (calibrateCamera, as left_intrinsics.yml was made: aspect ratio
// fixed) from its findChessboardCorners + cornerSubPix corners, made in the same run. The detector
// needs the lens only to straighten edges and to test that the grid is a plane; the set ships the
// left camera's calibration alone, and the right lens differs enough that its grids fail the plane
// test (0.5 px) with the left's.
CameraModel opencv_camera(const std::vector<std::vector<cv::Point2f>>& corners, cv::Size size, double& rms) {
  std::vector<std::vector<cv::Point3f>> object(corners.size());
  for (auto& o : object)
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 9; ++c) o.emplace_back(static_cast<float>(c), static_cast<float>(r), 0.0f);
  cv::Mat K = cv::Mat::eye(3, 3, CV_64F), D;
  std::vector<cv::Mat> rv, tv;
  rms = cv::calibrateCamera(object, corners, size, K, D, rv, tv, cv::CALIB_FIX_ASPECT_RATIO);
  Eigen::Matrix3d k;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) k(r, c) = K.at<double>(r, c);
  const Distortion d{D.at<double>(0), D.at<double>(1), D.at<double>(2), D.at<double>(3), D.at<double>(4)};
  return CameraModel(k, d, size.width, size.height);
}

// The board's plane as cornerSubPix's corners put it: the homography from the 9 x 6 grid to the
// undistorted corners (scaled by fx to pixels), fitted by least median of squares.
class BoardPlane {
 public:
  BoardPlane(const CameraModel& cam, const std::vector<cv::Point2f>& ref) : cam_(cam) {
    std::vector<cv::Point2f> undistorted;
    for (std::size_t j = 0; j < ref.size(); ++j) {
      grid_.emplace_back(static_cast<float>(j % 9), static_cast<float>(j / 9));
      undistorted.push_back(to_plane(Eigen::Vector2d(ref[j].x, ref[j].y)));
    }
    H_ = cv::findHomography(grid_, undistorted, cv::LMEDS);
  }
  bool ok() const { return !H_.empty(); }
  // How far the raw pixel p lies from where the plane puts grid corner j, in pixels.
  double residual(int j, const Eigen::Vector2d& p) const {
    std::vector<cv::Point2f> at;
    cv::perspectiveTransform(std::vector<cv::Point2f>{grid_[static_cast<std::size_t>(j)]}, at, H_);
    const cv::Point2f u = to_plane(p);
    return std::hypot(at[0].x - u.x, at[0].y - u.y);
  }

 private:
  cv::Point2f to_plane(const Eigen::Vector2d& px) const {
    const Eigen::Vector2d n = cam_.undistort(px).normalized * cam_.fx();
    return {static_cast<float>(n.x()), static_cast<float>(n.y())};
  }
  const CameraModel& cam_;
  std::vector<cv::Point2f> grid_;
  cv::Mat H_;
};

struct Image {
  std::string name;
  cv::Mat gray;
  std::vector<cv::Point2f> ref;  // OpenCV's corners: findChessboardCorners + cornerSubPix
};
struct PhotoSet {
  std::vector<Image> eyes[2];
  std::vector<std::vector<cv::Point2f>> refs[2];
};

// OpenCV's corners of every image first: they calibrate each eye for the detector. Loaded once per
// scale. Enlarged (`scale` > 1, cubic) the boards' squares grow to scale x 25-45 px, and the
// references are OpenCV's corners of the original, mapped to the enlarged pixels (centres at integers).
const PhotoSet& photo_set(int scale = 1) {
  static std::map<int, PhotoSet> sets;
  if (auto it = sets.find(scale); it != sets.end()) return it->second;
  return sets[scale] = [scale] {
    PhotoSet ps;
    for (int k = 1; k <= 14; ++k) {
      for (int e = 0; e < 2; ++e) {
        char name[64];
        std::snprintf(name, sizeof name, "%s/%s%02d.jpg", kDir, e == 0 ? "left" : "right", k);
        if (!std::filesystem::exists(name)) continue;  // the set has no pair 10
        Image im{name, cv::imread(name, cv::IMREAD_GRAYSCALE), {}};
        if (!cv::findChessboardCorners(im.gray, cv::Size(9, 6), im.ref,
                                       cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE)) {
          ADD_FAILURE() << name << ": OpenCV finds no board";
          continue;
        }
        cv::cornerSubPix(im.gray, im.ref, cv::Size(11, 11), cv::Size(-1, -1),
                         cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 30, 0.01));
        if (scale > 1) {
          cv::resize(im.gray, im.gray, cv::Size(), scale, scale, cv::INTER_CUBIC);
          for (cv::Point2f& q : im.ref) q = (q + cv::Point2f(0.5f, 0.5f)) * scale - cv::Point2f(0.5f, 0.5f);
        }
        ps.refs[e].push_back(im.ref);
        ps.eyes[e].push_back(std::move(im));
      }
    }
    return ps;
  }();
}

// Every board of the set found, every unflagged corner within 0.3 px (x scale) of cornerSubPix's or
// judged by the board's plane.
void check_photographs(int scale, int max_off_plane) {
  int off_plane = 0;
  const PhotoSet& set = photo_set(scale);
  const auto& eyes = set.eyes;
  const auto& refs = set.refs;
  const double agree_px = kAgreePx * scale, plane_slack_px = kPlaneSlackPx * scale;
  CornerSettings s;
  s.board.rows = 6;
  s.board.cols = 9;
  int images = 0, found = 0;
  double worst = 0, sum2 = 0;
  int n = 0, poor = 0, judged_by_plane = 0;
  double poor_worst = 0, plane_gain = 0, plane_worst = 0;
  for (int e = 0; e < 2; ++e) {
    double cal_rms = 0;
    const CameraModel cam = opencv_camera(refs[e], eyes[e].front().gray.size(), cal_rms);
    std::printf("OpenCV's calibration of the %s eye: fx %.2f px, RMS %.3f px\n", e == 0 ? "left" : "right",
                cam.fx(), cal_rms);
    CornerDetector det(cam, s);
    for (const Image& im : eyes[e]) {
      ++images;
      const cv::Mat& gray = im.gray;
      const char* name = im.name.c_str();
      const std::vector<cv::Point2f>& ref = im.ref;
      const test::PhotoFrame frame = test::photo_frame(gray);
      const RawImageView v = frame.view();
      CornerResult res;
      const bool ok = det.detect_full(v, res);
      if (!ok) std::printf("%s: not found (%s)\n", name, to_string(det.last_failure()));
      if (!ok) continue;
      ++found;
      const BoardPlane plane(cam, ref);
      ASSERT_TRUE(plane.ok()) << name << ": no homography from cornerSubPix's corners";
      for (int i = 0; i < res.count; ++i) {
        const Eigen::Vector2d p = res.corners[static_cast<std::size_t>(i)].px;
        double best = 1e30;
        int nearest = 0;
        for (int j = 0; j < static_cast<int>(ref.size()); ++j) {
          const double d = std::hypot(p.x() - ref[static_cast<std::size_t>(j)].x,
                                      p.y() - ref[static_cast<std::size_t>(j)].y);
          if (d < best) {
            best = d;
            nearest = j;
          }
        }
        // A corner the model does not describe (kCornerFitPoor) is flagged, not trusted: only the
        // others must agree with cornerSubPix.
        if (res.corners[static_cast<std::size_t>(i)].flags & kCornerFitPoor) {
          ++poor;
          poor_worst = std::max(poor_worst, best);
          continue;
        }
        if (best > agree_px) {
          // cornerSubPix's corner can be drawn off a junction whose edges do not meet in one point
          // (the board's broken border row): the plane says which of the two is the board's.
          const cv::Point2f& q = ref[static_cast<std::size_t>(nearest)];
          const double ours_off = plane.residual(nearest, p);
          const double theirs_off = plane.residual(nearest, Eigen::Vector2d(q.x, q.y));
          // And within twice the lens calibration's own RMS of the plane: the plane is no better
          // than the lens it undistorts with (0.41 / 0.46 px), and a corner off by more is wrong
          // whatever cornerSubPix did.
          EXPECT_LE(ours_off, 2.0 * cal_rms) << name << " corner " << i;
          if (ours_off > theirs_off + plane_slack_px) {
            ++off_plane;
            std::printf(
                "%s corner %d: %.3f px from cornerSubPix's, %.3f px off the board's plane against "
                "its %.3f\n",
                name, i, best, ours_off, theirs_off);
          }
          ++judged_by_plane;
          plane_gain = std::max(plane_gain, theirs_off - ours_off);
          plane_worst = std::max(plane_worst, ours_off);
          continue;
        }
        worst = std::max(worst, best);
        sum2 += best * best;
        ++n;
      }
    }
  }
  std::printf(
      "photographs x %d: %d/%d images found; %d corners within %.1f px of cornerSubPix (%.3f px RMS, worst "
      "%.3f px); %d farther, judged by the board's plane (ours at most %.2f px off it, cornerSubPix's up "
      "to %.2f px farther than ours); %d flagged poor (worst %.2f px from cornerSubPix's)\n",
      scale, found, images, n, agree_px, n ? std::sqrt(sum2 / n) : 0.0, worst, judged_by_plane, plane_worst,
      plane_gain, poor, poor_worst);
  EXPECT_EQ(images, 26);
  EXPECT_EQ(found, 26);  // the target: every board in both eyes
  // JPEG misfits every corner of a frame alike (6-13 % of the contrast): the poor flag marks a
  // frame's outliers, not the frame (it flagged 1339 of 1350 when it was a fixed 5 %).
  EXPECT_LE(20 * poor, n + judged_by_plane + poor);
  EXPECT_LE(off_plane, max_off_plane);
}

TEST(Photographs, OpenCvSampleSetEveryCornerWithinPointThreePxOfCornerSubPix) {
  if (!std::filesystem::exists(std::string(kDir) + "/left01.jpg")) {
    GTEST_SKIP() << "opencv-doc is not installed (scripts/install-deps.sh installs it)";
  }
  check_photographs(1, 0);
}

// Any scale: the same photographs enlarged twice, 1280 x 960 with squares of 50-90 px (the issue asks
// for 60 px) and edges blurred to ~2 px. Found through the detector's next pyramid level (7 of 26
// before it, at this level alone); the tolerances scale with the image. The enlarged image is not
// the original: cubic interpolation's ringing and the level's 2 x 2 binning move a few corners at
// the boards' broken border junctions (docs/corners.md, "Real photographs"): 3 of the 1404 are
// farther from the plane than cornerSubPix's by more than the slack (left13 and right07 corner 8,
// right08 corner 52: 0.14-0.74 px beyond it), all within twice the lens's RMS of the plane.
TEST(Photographs, TheSameSetEnlargedTwiceIsFoundAsWell) {
  if (!std::filesystem::exists(std::string(kDir) + "/left01.jpg")) {
    GTEST_SKIP() << "opencv-doc is not installed (scripts/install-deps.sh installs it)";
  }
  check_photographs(2, 3);
}

// Far boards in photographs nobody here rendered: the same set reduced (area average) by `factor`,
// squares of (25-45) / factor px. Prints, per factor, the boards ours and OpenCV's
// findChessboardCorners find on the reduced images, and ours against cornerSubPix's corners of the
// originals mapped onto the reduced pixels.
struct ReducedFigures {
  int images = 0, ours = 0, opencv = 0, corners = 0, flagged = 0, beyond = 0;
  int off_plane = 0;           // of `beyond`: farther from the board's plane than cornerSubPix's
  double rms = 0, worst = 0;   // over the corners within beyond_px
  double worst_off_plane = 0;  // of `beyond`: ours from the plane (px)
};
ReducedFigures check_reduced(int factor, double beyond_px) {
  const PhotoSet& full = photo_set(1);
  ReducedFigures f;
  double sum2 = 0;
  CornerSettings s;
  s.board.rows = 6;
  s.board.cols = 9;
  for (int e = 0; e < 2; ++e) {
    std::vector<Image> eye;
    std::vector<std::vector<cv::Point2f>> refs;
    for (const Image& im : full.eyes[e]) {
      Image r{im.name, {}, im.ref};
      cv::resize(im.gray, r.gray, cv::Size(im.gray.cols / factor, im.gray.rows / factor), 0, 0,
                 cv::INTER_AREA);
      // INTER_AREA maps the whole image onto the whole image: its scale is the sizes' ratio (640 / 91
      // for 1/7), not the factor.
      const float sx = static_cast<float>(r.gray.cols) / static_cast<float>(im.gray.cols);
      const float sy = static_cast<float>(r.gray.rows) / static_cast<float>(im.gray.rows);
      for (cv::Point2f& q : r.ref) q = cv::Point2f((q.x + 0.5f) * sx - 0.5f, (q.y + 0.5f) * sy - 0.5f);
      refs.push_back(r.ref);
      eye.push_back(std::move(r));
    }
    double cal_rms = 0;
    const CameraModel cam = opencv_camera(refs, eye.front().gray.size(), cal_rms);
    CornerDetector det(cam, s);
    for (const Image& im : eye) {
      ++f.images;
      std::vector<cv::Point2f> cv_corners;
      f.opencv += cv::findChessboardCorners(im.gray, cv::Size(9, 6), cv_corners,
                                            cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
      const test::PhotoFrame frame = test::photo_frame(im.gray);
      const RawImageView v = frame.view();
      CornerResult res;
      if (!det.detect_full(v, res)) {
        const CornerRejection& j = det.last_rejection();
        std::printf("  x1/%d %s: not found (%s; corner %d, rms %.1f DN against %.1f)\n", factor,
                    im.name.c_str(), to_string(det.last_failure()), j.index, j.rms, j.bound_rms);
        continue;
      }
      ++f.ours;
      const BoardPlane plane(cam, im.ref);
      for (int i = 0; i < res.count; ++i) {
        const Corner& c = res.corners[static_cast<std::size_t>(i)];
        double best = 1e30;
        int nearest = 0;
        for (int j = 0; j < static_cast<int>(im.ref.size()); ++j) {
          const cv::Point2f& q = im.ref[static_cast<std::size_t>(j)];
          const double d = std::hypot(c.px.x() - q.x, c.px.y() - q.y);
          if (d < best) {
            best = d;
            nearest = j;
          }
        }
        if (c.flags & kCornerFitPoor) {
          ++f.flagged;
          continue;
        }
        ++f.corners;
        if (best > beyond_px) {
          // As at full size: where the two disagree the board's plane says which is the board's
          // (cornerSubPix's corners at the broken border junctions are off it by up to 6 px there).
          ++f.beyond;
          const cv::Point2f& q = im.ref[static_cast<std::size_t>(nearest)];
          const double ours_off = plane.residual(nearest, c.px);
          const double theirs_off = plane.residual(nearest, Eigen::Vector2d(q.x, q.y));
          f.worst_off_plane = std::max(f.worst_off_plane, ours_off);
          if (ours_off > theirs_off + kPlaneSlackPx) {
            ++f.off_plane;
            std::printf(
                "  x1/%d %s corner %d: %.3f px from cornerSubPix's, %.3f px off the plane against its %.3f\n",
                factor, im.name.c_str(), i, best, ours_off, theirs_off);
          }
          continue;
        }
        f.worst = std::max(f.worst, best);
        sum2 += best * best;
      }
    }
  }
  f.rms = f.corners ? std::sqrt(sum2 / f.corners) : 0.0;
  std::printf(
      "photographs x 1/%d (squares ~%.0f-%.0f px): ours %d/%d images, OpenCV's findChessboardCorners %d; "
      "%d unflagged corners, %.3f px RMS from cornerSubPix's of the originals, worst %.3f px, %d beyond "
      "%.2f px (judged by the board's plane: ours at most %.2f px off it, %d farther than cornerSubPix's); "
      "%d flagged\n",
      factor, 25.0 / factor, 45.0 / factor, f.ours, f.images, f.opencv, f.corners, f.rms, f.worst, f.beyond,
      beyond_px, f.worst_off_plane, f.off_plane, f.flagged);
  return f;
}

// Measured 2026-12-05 (docs/corners.md, "Far boards in photographs"): ours finds 25 / 20 / 11 / 5 of
// the 26 images at 1/4 / 1/5 / 1/6 / 1/7, OpenCV's findChessboardCorners 12 / 5 / 1 / 1 (ours found 0 /
// 1 / 4 / 2 before border corners got smaller windows where the outer squares end inside the
// window). Ours within 0.03-0.04 px RMS of cornerSubPix's; where farther than 0.25 px the board's
// plane judges, and cornerSubPix's is the one off it but for one corner of left12 at 1/6 (ours
// 0.25 px off the plane against its 0.03).
TEST(Photographs, TheSameSetReducedIsFoundAsOftenAsByOpenCvWithoutFalseCorners) {
  if (!std::filesystem::exists(std::string(kDir) + "/left01.jpg")) {
    GTEST_SKIP() << "opencv-doc is not installed (scripts/install-deps.sh installs it)";
  }
  int off_plane = 0;
  for (int factor : {4, 5, 6, 7}) {
    const ReducedFigures f = check_reduced(factor, 0.25);
    EXPECT_EQ(f.images, 26);
    EXPECT_GE(f.ours, f.opencv) << "1/" << factor << ": never fewer boards than OpenCV";
    EXPECT_LE(f.rms, 0.05) << "1/" << factor;
    EXPECT_LE(f.worst_off_plane, 0.3) << "1/" << factor << ": a false corner is 0.5 px off";
    off_plane += f.off_plane;
  }
  EXPECT_LE(off_plane, 1);
}

// Two boards in one view: left04 shows a 9 x 6 board on a monitor (squares of ~4.5 px) beside the
// held one. Once boards that small could be fitted (corners/sine_fit.hpp) the full search of the
// calibrate tool's first round (the plain pinhole guess, the plane test off) returned the monitor's,
// found first, and `naneye calibrate` failed on the set (a view whose board is another plane); the
// search now goes on past a board of few-pixel squares and returns the better-measured one.
TEST(Photographs, TheHeldBoardIsReturnedNotTheOneOnTheMonitor) {
  if (!std::filesystem::exists(std::string(kDir) + "/left01.jpg")) {
    GTEST_SKIP() << "opencv-doc is not installed (scripts/install-deps.sh installs it)";
  }
  Eigen::Matrix3d K;
  K << 640, 0, 319.5, 0, 640, 239.5, 0, 0, 1;
  CornerSettings s;
  s.board.rows = 6;
  s.board.cols = 9;
  s.max_homography_rms_px = s.max_homography_worst_px = std::numeric_limits<double>::infinity();
  CornerDetector det(CameraModel(K, Distortion{0, 0, 0, 0, 0}, 640, 480), s);
  int images = 0, held = 0;
  for (const auto& eye : photo_set().eyes) {
    for (const Image& im : eye) {
      ++images;
      const test::PhotoFrame frame = test::photo_frame(im.gray);
      CornerResult res;
      if (!det.detect_full(frame.view(), res)) continue;
      // The monitor's board has squares of ~4.5 px, the held one of 25-45 px.
      const double square = (res.corners[1].px - res.corners[0].px).norm();
      EXPECT_GT(square, 15.0) << im.name << ": the monitor's board, not the held one";
      held += square > 15.0;
    }
  }
  EXPECT_EQ(images, 26);
  EXPECT_EQ(held, 26);
}

// Never a false board: a larger board whose next row is partly hidden fits the smaller pattern in
// one place only, and the X-junctions of its visible next row are what says it is larger. The 9 x 6
// boards asked as 9 x 5: the first four corners of the last row are covered by grey discs, so the
// remaining five are that next row (the lines through them run on between real squares). Not one
// image may give a board (the right board would be rows 0-4, but nothing in the image says so).
TEST(Photographs, ALargerBoardWithItsNextRowPartlyHiddenIsNotTakenForTheSmallerPattern) {
  if (!std::filesystem::exists(std::string(kDir) + "/left01.jpg")) {
    GTEST_SKIP() << "opencv-doc is not installed (scripts/install-deps.sh installs it)";
  }
  const PhotoSet& set = photo_set();
  CornerSettings s;
  s.board.rows = 5;
  s.board.cols = 9;
  int images = 0, found = 0;
  for (int e = 0; e < 2; ++e) {
    double cal_rms = 0;
    CornerDetector det(opencv_camera(set.refs[e], set.eyes[e].front().gray.size(), cal_rms), s);
    for (const Image& im : set.eyes[e]) {
      cv::Mat gray = im.gray.clone();
      // OpenCV orders its corners from either end of the board: hide corners 0-3 of whichever row
      // comes last in its order; a disc of the local mean, 0.4 of the spacing across (no saddle left).
      const double spacing = cv::norm(im.ref[1] - im.ref[0]);
      for (int c = 0; c < 4; ++c) {
        const cv::Point2f q = im.ref[static_cast<std::size_t>(5 * 9 + c)];
        const int radius = static_cast<int>(std::lround(0.4 * spacing));
        const cv::Scalar mean = cv::mean(gray(
            cv::Rect(cv::Point(q) - cv::Point(radius, radius), cv::Size(2 * radius + 1, 2 * radius + 1)) &
            cv::Rect(0, 0, gray.cols, gray.rows)));
        cv::circle(gray, q, radius, mean, cv::FILLED, cv::LINE_AA);
      }
      const test::PhotoFrame frame = test::photo_frame(gray);
      const RawImageView v = frame.view();
      CornerResult res;
      ++images;
      const bool ok = det.detect_full(v, res);
      found += ok;
      EXPECT_FALSE(ok) << im.name << ": a 9 x 5 board found in a 9 x 6 board";
    }
  }
  std::printf("larger boards, next row partly hidden: %d of %d taken for the smaller pattern\n", found,
              images);
  EXPECT_EQ(images, 26);
}

}  // namespace
}  // namespace naneye::recon
