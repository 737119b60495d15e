#pragma once
// Exact rectification of the rig for the dense path (docs/scene.md, "Dense path"): both eyes
// re-imaged onto one virtual pinhole pair whose x axis is the baseline, so that epipolar curves
// become rows and a point at depth Z_rect has disparity u_l - u_r = f B / Z_rect. The maps come from
// the exact model (CameraModel::project / undistort, paper Eq. 3-6), cover each eye's whole valid
// domain (no alpha-0 crop) and mark every rectified pixel whose source lies beyond a fold or outside
// the active image as invalid. Built once per rig; nothing here runs per frame.
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <vector>

#include "naneye/recon/camera/rig.hpp"

namespace naneye::recon::scene {

struct RectifiedRig {
  // Virtual camera (same for both eyes): u = f X/Z + cx, v = f Y/Z + cy in the rectified frames.
  double f = 0, cx = 0, cy = 0;  // px
  double baseline_mm = 0;        // |C|, the right centre in the left frame
  int width = 0, height = 0;     // rectified image size
  // X_rect = R_left_rect X_left; X_rect_right = R_right_rect X_right = X_rect - (B, 0, 0).
  Eigen::Matrix3d R_left_rect = Eigen::Matrix3d::Identity(), R_right_rect = Eigen::Matrix3d::Identity();
  // Rectified pixel -> raw pixel of each eye (CV_32FC1 x / y; -1 where invalid).
  cv::Mat map_x[2], map_y[2];
  // The same as interpolation taps: raw index of the source pixel at (floor x, floor y) (-1:
  // invalid) and the fractional offsets. cv::remap quantises positions to 1/32 px (INTER_BITS = 5), a fixed
  // 0.009 px rms error per image, comparable with the disparity noise we aim at: resample() uses these.
  std::vector<int> tap[2];
  std::vector<float> frac_x[2], frac_y[2];
  // CV_8UC1, rectified grid: 1 where the source pixel and its interpolation taps lie inside the
  // eye's model domain and its active image.
  cv::Mat valid[2];
  // Left raw pixel -> rectified position (CV_32FC1 each; NaN beyond the left fold).
  cv::Mat raw_to_rect_x, raw_to_rect_y;
  double disparity_for(double z_rect_mm) const { return f * baseline_mm / z_rect_mm; }
  // Eye `eye`'s raw luminance (row-major, raw_width wide) onto the rectified grid (CV_32FC1,
  // preallocated width x height); invalid pixels get 0. Allocates nothing.
  void resample(int eye, const float* raw, int raw_width, cv::Mat& out) const;
};

// `active`: the raw pixels that carry image data (CV_8UC1 per eye, left raw grid size). The virtual
// focal length is the left camera's fx (the centre keeps its sampling; the periphery, compressed by
// the barrel distortion, is oversampled rather than lost).
// `pad_left_px`: columns added left of everything either eye sees, so that a matcher that cannot
// match the first (min + number of disparities) columns (SGBM) loses none of the left view.
RectifiedRig build_rectified_rig(const StereoRig& rig, const cv::Mat& active_left,
                                 const cv::Mat& active_right, int pad_left_px = 0);

}  // namespace naneye::recon::scene
