#pragma once
// Depth at one left-image raw pixel: that pixel's exact ray (CameraModel::undistort, the inverse of
// paper Eq. 5-6) intersected with the fitted board plane of a result.
#include <Eigen/Core>

#include "naneye/recon/camera/rig.hpp"
#include "naneye/recon/pair/result.hpp"
#include "naneye/recon/scene/dense.hpp"

namespace naneye::daemon {

enum class DepthAtStatus { ok, no_board, outside_model, no_convergence, parallel, behind_camera, off_board };
const char* to_string(DepthAtStatus s);

struct DepthAt {
  DepthAtStatus status = DepthAtStatus::no_board;
  Eigen::Vector3d xyz_mm{0, 0, 0};  // the intersection, left camera frame
  double depth_mm = 0;              // its Z
  double range_mm = 0;              // its distance from the left camera centre
  // One sigma of depth_mm: the standard error of the plane's offset along the ray, from the
  // per-corner depth sigmas of the board's valid corners (1 / sum(1 / s_i^2)), scaled by Z / d;
  // first order, the plane's tilt uncertainty is not included.
  double depth_sigma_mm = 0;
  Eigen::Vector2d board_xy_mm{0, 0};  // the intersection in the board frame
};

// The board counts as the rectangle spanned by its inner corners plus one square around them (the
// outer squares of the chessboard). `result.board` must be set for a number.
DepthAt depth_at(const recon::CameraModel& left, const recon::PairResult& result, const Eigen::Vector2d& px);

// Depth at a left raw pixel from a dense map (on the same raw grid): the map's value at the nearest
// pixel centre (the map holds one depth per pixel; nothing is interpolated across a pixel that has
// none), placed on that pixel centre's exact ray.
enum class DenseAtStatus { ok, outside_model, no_convergence, no_depth };
struct DenseDepthAt {
  DenseAtStatus status = DenseAtStatus::no_depth;
  int map_u = 0, map_v = 0;         // the map pixel used
  Eigen::Vector3d xyz_mm{0, 0, 0};  // left camera frame
  double depth_mm = 0, depth_sigma_mm = 0, range_mm = 0;
};
DenseDepthAt dense_depth_at(const recon::CameraModel& left, const recon::scene::DepthMap& map,
                            const Eigen::Vector2d& px);

}  // namespace naneye::daemon
