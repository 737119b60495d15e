#pragma once
// The Cramér-Rao bound of a dense disparity on a textured render: how precisely any matcher could
// find the shift between the eyes at each pixel, from the noise-free twin of the render and the
// sensor model's noise (docs/scene.md, "What any matcher could give"; bench_scene_limits,
// test_dense_bound).
//
// var(d) >= (sigma_l^2 + sigma_r^2) / sum_k g_k^2 over the window (Kay, "Fundamentals of Statistical
// Signal Processing: Estimation Theory", 1993, Sec. 3.11: the time-delay estimate), g the
// noise-free texture's slope along the left epipolar direction with the gain and offset between
// the eyes (L = a R + b, the dense matcher's model) projected out (their Fisher information removes
// that part of it), sigma^2 the sensor model's per-pixel variance at the noise-free signal (the
// right eye's taken as the left's: the eyes see the same surface), converted from raw pixels along
// the curve to the rectified disparity (d = f B w, f the left fx: the dense path's rectification)
// through the right curve's speed |d x_r / d w| at the true depth. Mono renders only (a Bayer
// luminance's noise is filtered: its bound needs the filter's correlation).
#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "naneye/recon/camera/rig.hpp"
#include "naneye/sim/sensor.hpp"

namespace naneye::sim {

// Per-pixel noise variance of one eye at a noise-free value (DN^2): the sensor model's shot and read
// noise (sim/src/sensor.cpp), its fixed patterns (independent between the eyes, so noise to a
// matcher) and the 10-bit quantisation.
double noise_variance_dn2(const SensorSettings& s, double clean_dn);

// The bound per left raw pixel, rectified disparity px (CV_64FC1), over the (2 r + 1)^2 window's
// pixels that see the surface; NaN where `truth` (the render's depth, NaN where not both eyes see
// the surface) has none or the window holds no slope. `clean_left`: the noise-free twin's left raw
// frame (CV_16UC1, noise_free_twin below). Throws std::invalid_argument for a Bayer sensor or
// mismatched images.
cv::Mat disparity_bound(const recon::StereoRig& rig, const SensorSettings& sensor, const cv::Mat& clean_left,
                        const cv::Mat& truth, int r);

// A depth's sigma at a left raw pixel as the dense path's rectified disparity sigma (what the bound
// is in): sigma_d = sigma_Z d / Z, d = f B / Z_rect. NaN beyond the left fold.
double disparity_sigma(const recon::StereoRig& rig, const Eigen::Vector2d& left_px, double z_mm,
                       double sigma_z_mm);

// The same light, blur and exposure without temporal noise, fixed patterns, defects or the reset
// line: the noise-free signal the bound's slopes and noise_variance_dn2 are taken from (defects and
// the reset line are left out of the bound: a few pixels and rows).
SensorSettings noise_free_twin(const SensorSettings& s);

}  // namespace naneye::sim
