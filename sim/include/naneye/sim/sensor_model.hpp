#pragma once
// The sensor step every renderer shares: the light on the pixels (CV_32FC1, 1.0 = a white square
// facing the camera on axis at the light's reference distance) -> the 10-bit raw frame the camera
// delivers (optical blur, Bayer sites, exposure, fixed-pattern noise, the reset line, shot and read
// noise, quantisation, defects, reference pixels and padding; docs/simulator.md gives each figure's
// source). The die's own patterns (defect positions, FPN) are fixed per sensor from defect_seed.
#include <cstdint>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "naneye/sim/sensor.hpp"

namespace naneye::sim {

// One generator for everything random (noise, poses, timing); the same seed gives the same bytes.
using Rng = std::mt19937_64;

class SensorModel {
 public:
  explicit SensorModel(const SensorSettings& settings);

  const SensorSettings& settings() const { return s_; }

  // Working images reused from frame to frame (one per rendering thread).
  struct Scratch {
    cv::Mat blurred, noise;
  };

  // eye 0 (left) or 1 (right): each die has its own fixed patterns. Draws one number from `rng`
  // when the settings have noise (the seed of OpenCV's per-pixel normals), none otherwise.
  // out: 250 x 250 row-major.
  void expose(int eye, const cv::Mat& light, Rng& rng, Scratch& scratch, std::uint16_t* out) const;

 private:
  SensorSettings s_;
  std::vector<int> defects_[2];  // pixel indices; value in defect_values_
  std::vector<std::uint16_t> defect_values_[2];
  std::vector<float> fpn_offset_[2], fpn_gain_[2];  // per pixel; empty without fixed-pattern noise
};

}  // namespace naneye::sim
