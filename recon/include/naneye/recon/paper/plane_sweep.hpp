#pragma once
// Plane sweeping (Collins, CVPR 1996; Gallup et al., CVPR 2007) on corners, applied "naively, in a direct
// way" as Dias et al. (ICDSC 2016, Sec. 4.2) did after division-model undistortion in pixel coordinates.
//
// Naive here means: the images (here: the corner positions) are undistorted first and the sweep then
// treats the cameras as pinholes; the planes are fronto-parallel to the left camera (n = (0, 0, 1)) at
// uniformly spaced depths z_min, z_min + step, ..., z_max (not uniform in disparity, not adapted to the
// distortion or to the region of space, the paper's stated future work); each corner independently takes
// the plane whose induced homography H(z) = K' (R + T n^T / z) K^-1 carries its left point closest to its
// right point (winner takes all, no aggregation). Optional sub-step refinement: a parabola through the
// squared transfer errors of the best plane and its two neighbours.

#include <Eigen/Core>
#include <span>
#include <vector>

#include "naneye/recon/paper/division_rig.hpp"

namespace naneye::recon {

struct PlaneSweepSettings {
  double z_min_mm = 5.0;  // the NanEye's depth of focus starts at 5 mm (paper Table 1)
  double z_max_mm = 150.0;
  double step_mm = 0.1;
  bool parabolic = true;  // sub-step interpolation
};

struct SweepHit {
  bool ok = false;             // false for an invalid pixel or an empty sweep
  bool at_range_end = false;   // the best plane is the first or last one: the true depth may lie outside
  double depth_mm = 0;         // Z in the left frame
  double transfer_px = 0;      // transfer error at the chosen (unrefined) plane
  Eigen::Vector3d X{0, 0, 0};  // on the left ray at depth_mm
};

// The sweep on undistorted pixels of a pinhole rig (rig.left/right distortion is ignored: pass
// DivisionRig::pinhole() or any rig whose K, R, T are wanted).
std::vector<SweepHit> plane_sweep_corners(const StereoRig& pinhole,
                                          std::span<const Eigen::Vector2d> left_px_u,
                                          std::span<const Eigen::Vector2d> right_px_u,
                                          const PlaneSweepSettings& settings = {});

// The paper's pipeline: undistort raw pixels with the division rig (Eq. 7), then sweep on its pinhole rig.
std::vector<SweepHit> plane_sweep_division(const DivisionRig& rig, std::span<const Eigen::Vector2d> px_left,
                                           std::span<const Eigen::Vector2d> px_right,
                                           const PlaneSweepSettings& settings = {});

// Convenience: the points of the hits, NaN where !ok (for the metrics of metrics.hpp).
std::vector<Eigen::Vector3d> sweep_points(std::span<const SweepHit> hits);

}  // namespace naneye::recon
