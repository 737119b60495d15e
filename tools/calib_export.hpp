#pragma once
// `naneye calib export`: a calibration in the formats of the tools users already have. The model is
// OpenCV's five-parameter one (k1 k2 p1 p2 k3), so every format below holds it exactly; numbers are
// written with 17 significant digits, so a file read back projects as the source does to the last bit.
#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

#include "naneye/recon/camera/rig.hpp"

namespace naneye::tools {

// The rectification of a rig (Bouguet's: each camera turned half of R about the axis of least
// rotation, then so that the baseline is the new x axis; as cv::stereoRectify). Derived from R and T
// alone: nothing here undistorts a pixel, so no pixel beyond a camera's fold can spoil it (OpenCV's
// stereoRectify undistorts the image corners with its 5-iteration default to pick the new focal).
// P1, P2 share f (the left camera's fx) and the principal point (the mean of the two); P2's (0, 3)
// entry is f * t_x, t_x the right camera's rectified x offset in mm (-baseline when it sits at +x),
// as ROS and OpenCV expect.
struct Rectification {
  Eigen::Matrix3d R1, R2;
  Eigen::Matrix<double, 3, 4> P1, P2;
  Eigen::Matrix4d Q;  // disparity-to-depth, as cv::stereoRectify's
};
Rectification rectify(const recon::StereoRig& rig);

// Writes DIR/left.yaml and DIR/right.yaml (ROS camera_info, distortion_model plumb_bob).
std::vector<std::filesystem::path> export_ros(const recon::StereoRig& rig, const std::filesystem::path& dir);
// Writes DIR/stereo.yml (OpenCV FileStorage: M1 D1 M2 D2 R T R1 R2 P1 P2 Q image_width image_height).
std::vector<std::filesystem::path> export_opencv(const recon::StereoRig& rig,
                                                 const std::filesystem::path& dir);
// Writes DIR/left.cameramodel and DIR/right.cameramodel (mrcal, LENSMODEL_OPENCV5; extrinsics are
// rt_cam_ref with the left camera as the reference, translation in mm).
std::vector<std::filesystem::path> export_mrcal(const recon::StereoRig& rig,
                                                const std::filesystem::path& dir);

}  // namespace naneye::tools
