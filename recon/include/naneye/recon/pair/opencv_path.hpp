#pragma once
// The reconstruction a competent OpenCV user would write for this rig (the reference our figures are compared
// with): findChessboardCorners (ADAPTIVE_THRESH | NORMALIZE_IMAGE) + cornerSubPix on each eye's luminance,
// cv::undistortPoints with each camera's K and D (default criteria: 5 fixed-point iterations), and
// cv::triangulatePoints with P1 = [I|0], P2 = [R|T] on the normalized coordinates. Benchmarks and
// tests compare our path (StereoReconstructor) against it; nothing in the product uses it.
//
// Choices a user has to make, made as the OpenCV documentation and samples make them:
//  - 10-bit luminance -> 8 bit for findChessboardCorners by a min-max stretch (cv::normalize);
//    cornerSubPix then runs on the float luminance (no 8-bit quantization: the favourable choice).
//  - cornerSubPix window: half-size 3 (a 7 x 7 window), the one /work/shared/notes/measurements.md
//    measured; the tutorial's 11 x 11 half-size would span more than a square at ~70 mm, where the
//    corners are 13-20 px apart. Criteria as in the calibration tutorial: 30 iterations or 0.001 px.
//  - The 180-degree ambiguity of an odd x odd board: findChessboardCorners may number the right
//    eye's grid from the opposite corner. A user reverses the right list when the first-to-last
//    corner vectors of the two eyes point opposite ways (the ~1 mm baseline keeps both views nearly
//    identical, so this is reliable here). The pair's numbering is then turned as a whole to our
//    CornerDetector's convention (canonical_order), so that ids compare with ours and the truth.
#include <Eigen/Core>
#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>
#include <vector>

#include "naneye/recon/camera/rig.hpp"
#include "naneye/recon/corners/detector.hpp"

namespace naneye::recon {

struct OpenCvPathSettings {
  BoardGeometry board;
  int subpix_half_window = 3;  // cornerSubPix winSize = (h, h): a (2h+1) x (2h+1) window
};

// The rig as OpenCV's calib3d takes it (CV_64F): camera matrices, distCoeffs in OpenCV's order,
// X_right = R X_left + T.
struct OpenCvRig {
  cv::Mat K1, D1, K2, D2, R, T;
};
OpenCvRig opencv_rig(const StereoRig& rig);

struct OpenCvPathResult {
  bool found = false;  // both eyes found the whole grid
  // Row-major over the pattern (id = row * cols + col), ids agreeing between the eyes; empty when
  // not found. xyz_mm in the left camera frame.
  std::vector<cv::Point2d> left_px, right_px;
  std::vector<Eigen::Vector3d> xyz_mm;
};

// The whole OpenCV path for one raw stereo pair (mono or GRBG Bayer: the luminance comes from
// raw_to_luminance, as for our detector, so both paths see the same pixels).
OpenCvPathResult opencv_reconstruct_pair(const StereoRig& rig, const RawImageView& left,
                                         const RawImageView& right, const OpenCvPathSettings& options = {});

}  // namespace naneye::recon
