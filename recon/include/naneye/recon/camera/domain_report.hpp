#pragma once
// What `naneye calib info` reports of one camera: its valid domain over the image and how exactly
// undistort() inverts distort() there.
#include <optional>

#include "naneye/recon/camera/camera_model.hpp"

namespace naneye::recon {

struct DomainReport {
  std::optional<double> fold_radius_px;  // empty when the model never folds
  int pixels_total = 0;
  int pixels_valid = 0;  // pixel centres inside the valid domain
  double valid_share() const { return pixels_total ? static_cast<double>(pixels_valid) / pixels_total : 0.0; }
  double max_roundtrip_error_px = 0.0;  // max |distort(undistort(p)) - p| over the valid pixel centres
  int max_iterations = 0;
};

// Visits every pixel centre (integer coordinates) of the camera's image.
DomainReport analyze_domain(const CameraModel& cam);

// |to_pixel(distort(undistort(px))) - px| in pixels; empty when px is outside the domain.
std::optional<double> roundtrip_error_px(const CameraModel& cam, const Eigen::Vector2d& px);

}  // namespace naneye::recon
