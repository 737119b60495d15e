#include "naneye/recon/pair/reconstruction.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "naneye/recon/geometry/calibration_uncertainty.hpp"
#include "naneye/recon/geometry/metrics.hpp"

namespace naneye::recon {

double measured_corner_sigma(const BoardPose& pose, const ReconstructionSettings& settings) {
  const int dof = pose.residuals - 6;
  if (!pose.ok || dof < 2) return settings.corner_sigma_px;
  // rms_px is over points (2 coordinates each): cost = rms^2 * residuals / 2.
  const double cost = pose.rms_px * pose.rms_px * pose.residuals / 2.0;
  return std::max(settings.min_corner_sigma_px, std::sqrt(cost / dof));
}

void reconstruct_pair(const StereoRig& rig, const BoardGeometry& b, const ReconstructionSettings& s,
                      std::span<const CornerObservation> obs, PairResult& out) {
  out.board_found = false;
  out.board.reset();
  out.metrics.reset();
  out.point_count = static_cast<int>(std::min<std::size_t>(obs.size(), kMaxCorners));

  // The pose first: its residuals measure this pair's corner noise, which then sets every sigma.
  // With sigma 1 the covariance is (J^T J)^-1, scaled by the measured sigma^2 below.
  BoardPose pose = estimate_board_pose(rig, b, obs.first(static_cast<std::size_t>(out.point_count)), 1.0);
  const double sigma = measured_corner_sigma(pose, s);
  pose.covariance *= sigma * sigma;

  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto calib = CalibrationUncertainty::of(rig);  // empty without a covariance; no heap
  std::array<Eigen::Vector3d, kMaxCorners> grid;
  std::array<Eigen::Vector2d, kMaxCorners> pl, pr;
  grid.fill(Eigen::Vector3d::Constant(nan));
  int valid = 0;
  for (int i = 0; i < out.point_count; ++i) {
    const CornerObservation& o = obs[static_cast<std::size_t>(i)];
    PointResult& p = out.points[static_cast<std::size_t>(i)];
    p = PointResult{};
    p.row = o.row;
    p.col = o.col;
    p.id = o.row * b.cols + o.col;
    p.left_px = o.left_px;
    p.right_px = o.right_px;
    pl[static_cast<std::size_t>(i)] = o.left_px;
    pr[static_cast<std::size_t>(i)] = o.right_px;
    if (pose.ok) p.xyz_board_mm = pose.to_camera(b.corner(o.row, o.col));
    if (!o.left_ok || !o.right_ok) continue;
    const Triangulated t = triangulate(rig, o.left_px, o.right_px, s.method, sigma);
    if (!t.ok()) continue;
    p.valid = true;
    p.xyz_mm = t.X;
    p.depth_sigma_mm = t.depth_sigma_mm;
    if (calib) p.calib_sigma_mm = calib->depth_sigma_mm(t.X);
    if (o.row >= 0 && o.row < b.rows && o.col >= 0 && o.col < b.cols && p.id < kMaxCorners)
      grid[static_cast<std::size_t>(p.id)] = t.X;
    ++valid;
  }
  if (!pose.ok) return;

  BoardResult br;
  br.rotation = pose.R;
  br.translation_mm = pose.t;
  br.normal = pose.normal();
  br.distance_mm = pose.plane_distance_mm();
  br.rms_px = pose.rms_px;
  out.board = br;
  out.board_found = true;

  if (valid < 3) return;
  const std::size_t n = static_cast<std::size_t>(b.rows * b.cols);
  std::array<Eigen::Vector3d, kMaxCorners> pts;
  for (int i = 0; i < out.point_count; ++i) {
    const PointResult& p = out.points[static_cast<std::size_t>(i)];
    pts[static_cast<std::size_t>(i)] = p.valid ? p.xyz_mm : Eigen::Vector3d::Constant(nan);
  }
  const std::span<const Eigen::Vector3d> triangulated(pts.data(), static_cast<std::size_t>(out.point_count));
  MetricsResult m;
  m.planarity_mm = planarity_error(triangulated).value_or(nan);
  m.distance_error_mm = n <= kMaxCorners ? distance_error(std::span<const Eigen::Vector3d>(grid.data(), n),
                                                          b.rows, b.cols, b.square_mm)
                                               .value_or(nan)
                                         : nan;
  m.reprojection_px =
      reprojection_error(rig, triangulated, std::span<const Eigen::Vector2d>(pl.data(), triangulated.size()),
                         std::span<const Eigen::Vector2d>(pr.data(), triangulated.size()))
          .value_or(nan);
  out.metrics = m;
}

}  // namespace naneye::recon
