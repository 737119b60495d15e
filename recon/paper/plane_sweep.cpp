#include "naneye/recon/paper/plane_sweep.hpp"

#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace naneye::recon {

std::vector<SweepHit> plane_sweep_corners(const StereoRig& pinhole,
                                          std::span<const Eigen::Vector2d> left_px_u,
                                          std::span<const Eigen::Vector2d> right_px_u,
                                          const PlaneSweepSettings& s) {
  if (left_px_u.size() != right_px_u.size()) throw std::invalid_argument("plane_sweep_corners: sizes differ");
  if (!(s.step_mm > 0.0) || !(s.z_min_mm > 0.0) || !(s.z_max_mm >= s.z_min_mm)) {
    throw std::invalid_argument("plane_sweep_corners: need 0 < z_min <= z_max and step > 0");
  }
  const int planes = static_cast<int>(std::floor((s.z_max_mm - s.z_min_mm) / s.step_mm + 1e-9)) + 1;
  const Eigen::Matrix3d Kr = pinhole.right.K(), Kli = pinhole.left.K().inverse();
  std::vector<SweepHit> hits(left_px_u.size());
  std::vector<double> e2(static_cast<std::size_t>(planes));
  for (std::size_t i = 0; i < hits.size(); ++i) {
    if (!left_px_u[i].allFinite() || !right_px_u[i].allFinite()) continue;
    // For n = (0, 0, 1) and x = K^-1 p normalised to x.z = 1: H(z) p ~ K' R x + K' T / z = a + b / z.
    const Eigen::Vector3d x = Kli * left_px_u[i].homogeneous();
    const Eigen::Vector3d xn = x / x.z();
    const Eigen::Vector3d a = Kr * pinhole.R * xn, b = Kr * pinhole.T;
    int best = -1;
    for (int k = 0; k < planes; ++k) {
      const double z = s.z_min_mm + k * s.step_mm;
      const Eigen::Vector3d p = a + b / z;
      e2[static_cast<std::size_t>(k)] = p.z() > 0.0 ? (p.head<2>() / p.z() - right_px_u[i]).squaredNorm()
                                                    : std::numeric_limits<double>::infinity();
      if (best < 0 || e2[static_cast<std::size_t>(k)] < e2[static_cast<std::size_t>(best)]) best = k;
    }
    if (best < 0 || !std::isfinite(e2[static_cast<std::size_t>(best)])) continue;
    SweepHit& h = hits[i];
    h.ok = true;
    h.transfer_px = std::sqrt(e2[static_cast<std::size_t>(best)]);
    h.at_range_end = best == 0 || best == planes - 1;
    double z = s.z_min_mm + best * s.step_mm;
    if (s.parabolic && !h.at_range_end) {
      const double em = e2[static_cast<std::size_t>(best - 1)], e0 = e2[static_cast<std::size_t>(best)],
                   ep = e2[static_cast<std::size_t>(best + 1)];
      const double curvature = em - 2.0 * e0 + ep;
      if (curvature > 0.0) z += 0.5 * (em - ep) / curvature * s.step_mm;
    }
    h.depth_mm = z;
    h.X = z * xn;
  }
  return hits;
}

std::vector<SweepHit> plane_sweep_division(const DivisionRig& rig, std::span<const Eigen::Vector2d> px_left,
                                           std::span<const Eigen::Vector2d> px_right,
                                           const PlaneSweepSettings& settings) {
  if (px_left.size() != px_right.size()) throw std::invalid_argument("plane_sweep_division: sizes differ");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<Eigen::Vector2d> ul(px_left.size()), ur(px_right.size());
  for (std::size_t i = 0; i < px_left.size(); ++i) {
    ul[i] = rig.left.undistort_pixel(px_left[i]).value_or(Eigen::Vector2d(nan, nan));
    ur[i] = rig.right.undistort_pixel(px_right[i]).value_or(Eigen::Vector2d(nan, nan));
  }
  return plane_sweep_corners(rig.pinhole(), ul, ur, settings);
}

std::vector<Eigen::Vector3d> sweep_points(std::span<const SweepHit> hits) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(hits.size());
  for (const auto& h : hits) {
    out.push_back(h.ok ? h.X : Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
  }
  return out;
}

}  // namespace naneye::recon
