// Exact rectification maps for the dense path (dense_rectify.hpp).
#include "dense_rectify.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "naneye/recon/scene/rectified_axes.hpp"
#include "resample_kernels.hpp"

namespace naneye::recon::scene {
namespace {

// The raw pixel a rectified-frame ray reaches, or false when the ray lies behind the camera or
// beyond the model's fold (where project() would fold back onto pixels that see something else).
bool ray_to_raw(const CameraModel& cam, const Eigen::Vector3d& ray, Eigen::Vector2d& px) {
  if (ray.z() <= 0) return false;
  const Eigen::Vector2d xn = ray.head<2>() / ray.z();
  if (cam.fold_radius_undistorted() && xn.norm() >= *cam.fold_radius_undistorted()) return false;
  px = cam.to_pixel(cam.distort(xn));
  if (cam.distortion().has_tangential()) {
    // The tangential model's domain is checked per point: the exact inverse must give xn back.
    const Undistorted u = cam.undistort(px);
    if (!u.ok() || (u.normalized - xn).norm() > 1e-9) return false;
  }
  return true;
}

// Keys' cubic convolution reads the 4 x 4 pixels around the source position: all must carry data.
bool taps_active(const cv::Mat& active, const Eigen::Vector2d& px) {
  const int c = static_cast<int>(std::floor(px.x())), r = static_cast<int>(std::floor(px.y()));
  if (c < 1 || r < 1 || c + 2 >= active.cols || r + 2 >= active.rows) return false;
  for (int dr = -1; dr <= 2; ++dr)
    for (int dc = -1; dc <= 2; ++dc)
      if (!active.at<std::uint8_t>(r + dr, c + dc)) return false;
  return true;
}

}  // namespace

Eigen::Matrix3d rect_from_left(const StereoRig& rig) {
  const Eigen::Vector3d e1 = rig.right_center().normalized();
  const Eigen::Vector3d zl(0, 0, 1), zr = rig.R.transpose() * Eigen::Vector3d(0, 0, 1);
  const Eigen::Vector3d e2 = (zl + zr).normalized().cross(e1).normalized();
  Eigen::Matrix3d R;
  R.row(0) = e1.transpose();
  R.row(1) = e2.transpose();
  R.row(2) = e1.cross(e2).transpose();
  return R;
}

RectifiedRig build_rectified_rig(const StereoRig& rig, const cv::Mat& active_left,
                                 const cv::Mat& active_right, int pad_left_px) {
  RectifiedRig out;
  out.baseline_mm = rig.right_center().norm();
  // One rotation for both eyes (rectified_axes.hpp) keeps both views' periphery equally stretched.
  out.R_left_rect = rect_from_left(rig);
  out.R_right_rect = out.R_left_rect * rig.R.transpose();
  out.f = rig.left.fx();

  // Extent: every raw pixel of either eye inside its domain, in rectified coordinates; columns the
  // left view's (a right pixel outside them matches no left pixel; the pad adds the band to its
  // left), rows the overlap (a row only one eye sees has no match).
  const CameraModel* cams[2] = {&rig.left, &rig.right};
  const cv::Mat* active[2] = {&active_left, &active_right};
  const Eigen::Matrix3d* rots[2] = {&out.R_left_rect, &out.R_right_rect};
  double xmin = 1e9, xmax = -1e9, ymin[2] = {1e9, 1e9}, ymax[2] = {-1e9, -1e9};
  for (int e = 0; e < 2; ++e)
    for (int r = 0; r < cams[e]->height(); ++r)
      for (int c = 0; c < cams[e]->width(); ++c) {
        if (!active[e]->at<std::uint8_t>(r, c)) continue;
        const Undistorted u = cams[e]->undistort(Eigen::Vector2d(c, r));
        if (!u.ok()) continue;
        const Eigen::Vector3d q = *rots[e] * Eigen::Vector3d(u.normalized.x(), u.normalized.y(), 1.0);
        if (q.z() <= 0) continue;
        const double x = out.f * q.x() / q.z(), y = out.f * q.y() / q.z();
        if (e == 0) {
          xmin = std::min(xmin, x);
          xmax = std::max(xmax, x);
        }
        ymin[e] = std::min(ymin[e], y);
        ymax[e] = std::max(ymax[e], y);
      }
  const double y0 = std::max(ymin[0], ymin[1]), y1 = std::min(ymax[0], ymax[1]);
  out.cx = std::ceil(-xmin) + pad_left_px;
  out.cy = std::ceil(-y0);
  out.width = static_cast<int>(std::ceil(xmax + out.cx)) + 1;
  out.height = static_cast<int>(std::ceil(y1 + out.cy)) + 1;

  for (int e = 0; e < 2; ++e) {
    out.map_x[e].create(out.height, out.width, CV_32FC1);
    out.map_y[e].create(out.height, out.width, CV_32FC1);
    out.valid[e] = cv::Mat::zeros(out.height, out.width, CV_8UC1);
    const Eigen::Matrix3d back = rots[e]->transpose();
    for (int v = 0; v < out.height; ++v)
      for (int u = 0; u < out.width; ++u) {
        const Eigen::Vector3d ray = back * Eigen::Vector3d((u - out.cx) / out.f, (v - out.cy) / out.f, 1.0);
        Eigen::Vector2d px;
        const bool ok = ray_to_raw(*cams[e], ray, px) && taps_active(*active[e], px);
        out.map_x[e].at<float>(v, u) = ok ? static_cast<float>(px.x()) : -1.f;
        out.map_y[e].at<float>(v, u) = ok ? static_cast<float>(px.y()) : -1.f;
        out.valid[e].at<std::uint8_t>(v, u) = ok ? 1 : 0;
      }
    const std::size_t n = static_cast<std::size_t>(out.width) * out.height;
    out.tap[e].assign(n, -1);
    out.frac_x[e].assign(n, 0.f);
    out.frac_y[e].assign(n, 0.f);
    for (int v = 0; v < out.height; ++v)
      for (int u = 0; u < out.width; ++u) {
        if (!out.valid[e].at<std::uint8_t>(v, u)) continue;
        const double x = out.map_x[e].at<float>(v, u), y = out.map_y[e].at<float>(v, u);
        const double c = std::floor(x), r = std::floor(y);
        const std::size_t i = static_cast<std::size_t>(v) * out.width + u;
        out.tap[e][i] = static_cast<int>(r) * cams[e]->width() + static_cast<int>(c);
        out.frac_x[e][i] = static_cast<float>(x - c);
        out.frac_y[e][i] = static_cast<float>(y - r);
      }
  }

  const float nan = std::numeric_limits<float>::quiet_NaN();
  out.raw_to_rect_x.create(rig.left.height(), rig.left.width(), CV_32FC1);
  out.raw_to_rect_y.create(rig.left.height(), rig.left.width(), CV_32FC1);
  for (int r = 0; r < rig.left.height(); ++r)
    for (int c = 0; c < rig.left.width(); ++c) {
      const Undistorted u = rig.left.undistort(Eigen::Vector2d(c, r));
      float x = nan, y = nan;
      if (u.ok()) {
        const Eigen::Vector3d q = out.R_left_rect * Eigen::Vector3d(u.normalized.x(), u.normalized.y(), 1.0);
        if (q.z() > 0) {
          x = static_cast<float>(out.f * q.x() / q.z() + out.cx);
          y = static_cast<float>(out.f * q.y() / q.z() + out.cy);
        }
      }
      out.raw_to_rect_x.at<float>(r, c) = x;
      out.raw_to_rect_y.at<float>(r, c) = y;
    }
  return out;
}

void RectifiedRig::resample(int eye, const float* raw, int raw_width, cv::Mat& out) const {
  // Keys' cubic, not bilinear: linear interpolation shifts a texture's phase with the fractional
  // position (up to 0.045 px at a 4 px wavelength), a fixed disparity error per rectified pixel as
  // large as the noise we aim at; the cubic's is about ten times smaller.
  resample::taps(raw, raw_width, tap[eye].data(), frac_x[eye].data(), frac_y[eye].data(),
                 static_cast<std::size_t>(width) * height, out.ptr<float>());
}

}  // namespace naneye::recon::scene
