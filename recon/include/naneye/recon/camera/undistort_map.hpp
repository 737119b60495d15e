#pragma once
// A per-camera table raw pixel -> undistorted normalized coordinates (the exact inverse of paper
// Eq. 5-6, CameraModel::undistort), built once per camera so that hot paths (the corner fit windows)
// read a window's undistorted coordinates instead of solving for them every frame.
#include <Eigen/Core>
#include <vector>

#include "naneye/recon/camera/camera_model.hpp"

namespace naneye::recon {

class UndistortMap {
 public:
  UndistortMap() = default;
  // Undistorts every pixel centre of the camera's width x height image (~60k Newton solves, a few
  // ms): do it at construction, never per frame.
  explicit UndistortMap(const CameraModel& cam);

  int width() const { return width_; }
  int height() const { return height_; }
  // Normalized coordinates of pixel (col, row); false beyond the model's fold (no undistorted point
  // maps there) or outside the image.
  bool at(int col, int row, float& x, float& y) const {
    if (col < 0 || row < 0 || col >= width_ || row >= height_) return false;
    const auto i = static_cast<std::size_t>(row * width_ + col);
    x = xy_[2 * i];
    y = xy_[2 * i + 1];
    return valid_[i] != 0;
  }
  // Row-major tables (width * height): x and y interleaved (a fit window reads both, from one
  // cache line), a pixel beyond the fold holds 0 and valid() == 0.
  const float* xy_data() const { return xy_.data(); }
  const unsigned char* valid_data() const { return valid_.data(); }

 private:
  int width_ = 0, height_ = 0;
  std::vector<float> xy_;
  std::vector<unsigned char> valid_;
};

}  // namespace naneye::recon
