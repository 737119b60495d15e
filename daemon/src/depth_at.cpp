#include "naneye/daemon/depth_at.hpp"
#include "naneye/base/enum_table.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace naneye::daemon {

namespace {
constexpr base::EnumTable<DepthAtStatus, 7> kDepthAtStatusNames{
    {{DepthAtStatus::ok, "ok"},
     {DepthAtStatus::no_board, "no_board"},
     {DepthAtStatus::outside_model, "outside_model"},
     {DepthAtStatus::no_convergence, "no_convergence"},
     {DepthAtStatus::parallel, "parallel"},
     {DepthAtStatus::behind_camera, "behind_camera"},
     {DepthAtStatus::off_board, "off_board"}}};
}  // namespace

const char* to_string(DepthAtStatus s) {
  return base::enum_name(kDepthAtStatusNames, s);
}

DepthAt depth_at(const recon::CameraModel& left, const recon::PairResult& result, const Eigen::Vector2d& px) {
  DepthAt out;
  if (!result.board_found || !result.board) return out;
  const auto& b = *result.board;
  const auto u = left.undistort(px);
  if (!u.ok()) {
    out.status = u.status == recon::UndistortStatus::outside_model ? DepthAtStatus::outside_model
                                                                   : DepthAtStatus::no_convergence;
    return out;
  }
  // The ray X = s (x_n, y_n, 1) meets the plane n.X = n.t at s = n.t / n.dir (Z = s).
  const Eigen::Vector3d dir(u.normalized.x(), u.normalized.y(), 1.0);
  const Eigen::Vector3d n = b.normal.normalized();
  const double ndir = n.dot(dir);
  if (std::abs(ndir) < 1e-9) {
    out.status = DepthAtStatus::parallel;
    return out;
  }
  const double s = n.dot(b.translation_mm) / ndir;
  if (!(s > 0)) {
    out.status = DepthAtStatus::behind_camera;
    return out;
  }
  out.xyz_mm = s * dir;
  out.depth_mm = s;
  out.range_mm = out.xyz_mm.norm();
  const Eigen::Vector3d q = b.rotation.transpose() * (out.xyz_mm - b.translation_mm);
  out.board_xy_mm = q.head<2>();

  // The board's extent from its valid corners, in the board frame, padded by one square.
  double xmin = std::numeric_limits<double>::infinity(), xmax = -xmin, ymin = xmin, ymax = -xmin;
  double square = std::numeric_limits<double>::infinity(), inv_var = 0;
  int valid = 0;
  for (int i = 0; i < result.point_count; ++i) {
    const auto& p = result.points[static_cast<std::size_t>(i)];
    if (!p.valid) continue;
    const Eigen::Vector3d c = b.rotation.transpose() * (p.xyz_board_mm - b.translation_mm);
    xmin = std::min(xmin, c.x()), xmax = std::max(xmax, c.x());
    ymin = std::min(ymin, c.y()), ymax = std::max(ymax, c.y());
    for (int k = 0; k < i; ++k) {
      const auto& o = result.points[static_cast<std::size_t>(k)];
      if (!o.valid) continue;
      const double d = (o.xyz_board_mm - p.xyz_board_mm).norm();
      if (d > 1e-9) square = std::min(square, d);
    }
    if (p.depth_sigma_mm > 0) inv_var += 1.0 / (p.depth_sigma_mm * p.depth_sigma_mm);
    ++valid;
  }
  if (valid < 2 || !std::isfinite(square) || q.x() < xmin - square || q.x() > xmax + square ||
      q.y() < ymin - square || q.y() > ymax + square) {
    out.status = DepthAtStatus::off_board;
    return out;
  }
  // Z = s and s = d / (n.dir): an offset error of the plane maps to depth through 1 / |n.dir|.
  const double plane_sigma = inv_var > 0 ? std::sqrt(1.0 / inv_var) : 0.0;
  out.depth_sigma_mm = plane_sigma / std::abs(ndir);
  out.status = DepthAtStatus::ok;
  return out;
}

DenseDepthAt dense_depth_at(const recon::CameraModel& left, const recon::scene::DepthMap& map,
                            const Eigen::Vector2d& px) {
  DenseDepthAt out;
  out.map_u = std::clamp(static_cast<int>(std::lround(px.x())), 0, std::max(0, map.width - 1));
  out.map_v = std::clamp(static_cast<int>(std::lround(px.y())), 0, std::max(0, map.height - 1));
  const auto u = left.undistort(Eigen::Vector2d(out.map_u, out.map_v));
  if (!u.ok()) {
    out.status = u.status == recon::UndistortStatus::outside_model ? DenseAtStatus::outside_model
                                                                   : DenseAtStatus::no_convergence;
    return out;
  }
  if (map.width <= 0 || map.height <= 0 || map.z_mm.size() < static_cast<std::size_t>(map.width) * map.height)
    return out;
  const float z = map.z_at(out.map_u, out.map_v);
  const float sigma = map.sigma_at(out.map_u, out.map_v);
  if (!std::isfinite(z) || !std::isfinite(sigma)) return out;
  out.depth_mm = z;
  out.depth_sigma_mm = sigma;
  out.xyz_mm = Eigen::Vector3d(u.normalized.x(), u.normalized.y(), 1.0) * static_cast<double>(z);
  out.range_mm = out.xyz_mm.norm();
  out.status = DenseAtStatus::ok;
  return out;
}

}  // namespace naneye::daemon
