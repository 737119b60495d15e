#include "naneye/recon/camera/undistort_map.hpp"

namespace naneye::recon {

UndistortMap::UndistortMap(const CameraModel& cam) : width_(cam.width()), height_(cam.height()) {
  const auto n = static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
  xy_.assign(2 * n, 0.0f);
  valid_.assign(n, 0);
  for (int r = 0; r < height_; ++r) {
    for (int c = 0; c < width_; ++c) {
      const Undistorted u = cam.undistort(Eigen::Vector2d(c, r));
      if (!u.ok()) continue;
      const auto i = static_cast<std::size_t>(r * width_ + c);
      // Float keeps ~1e-7 relative: ~3e-5 px at the image corners, far below the fit's noise.
      xy_[2 * i] = static_cast<float>(u.normalized.x());
      xy_[2 * i + 1] = static_cast<float>(u.normalized.y());
      valid_[i] = 1;
    }
  }
}

}  // namespace naneye::recon
