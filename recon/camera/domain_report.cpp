#include "naneye/recon/camera/domain_report.hpp"

#include <algorithm>

namespace naneye::recon {

std::optional<double> roundtrip_error_px(const CameraModel& cam, const Eigen::Vector2d& px) {
  const Undistorted u = cam.undistort(px);
  if (!u.ok()) return std::nullopt;
  return (cam.to_pixel(cam.distort(u.normalized)) - px).norm();
}

DomainReport analyze_domain(const CameraModel& cam) {
  DomainReport r;
  r.fold_radius_px = cam.fold_radius_px();
  for (int v = 0; v < cam.height(); ++v) {
    for (int u = 0; u < cam.width(); ++u) {
      ++r.pixels_total;
      const Eigen::Vector2d px(u, v);
      const Undistorted und = cam.undistort(px);
      if (!und.ok()) continue;
      ++r.pixels_valid;
      r.max_iterations = std::max(r.max_iterations, und.iterations);
      r.max_roundtrip_error_px =
          std::max(r.max_roundtrip_error_px, (cam.to_pixel(cam.distort(und.normalized)) - px).norm());
    }
  }
  return r;
}

}  // namespace naneye::recon
