#include "naneye/recon/paper/division_triangulation.hpp"
#include "naneye/base/enum_table.hpp"

#include <Eigen/SVD>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace naneye::recon {

namespace {
constexpr base::EnumTable<DirectSolve, 2> kDirectSolveNames{
    {{DirectSolve::per_point, "per_point"}, {DirectSolve::one_svd, "one_svd"}}};
}  // namespace

const char* to_string(DirectSolve s) {
  return base::enum_name(kDirectSolveNames, s);
}

DirectTriangulation triangulate_distorted(const DivisionRig& rig, std::span<const Eigen::Vector2d> px_left,
                                          std::span<const Eigen::Vector2d> px_right, DirectSolve solve) {
  if (px_left.size() != px_right.size()) throw std::invalid_argument("triangulate_distorted: sizes differ");
  const std::size_t n = px_left.size();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  DirectTriangulation out;
  out.points.assign(n, Eigen::Vector3d::Constant(nan));
  out.alpha2.assign(n, nan);
  out.valid.assign(n, false);
  std::vector<Eigen::Vector3d> x(n), a(n), b(n);
  std::vector<std::size_t> used;
  for (std::size_t i = 0; i < n; ++i) {
    if (!rig.left.in_domain(px_left[i]) || !rig.right.in_domain(px_right[i])) continue;
    x[i] = rig.left.ray(px_left[i]);
    const Eigen::Matrix3d S = skew(rig.right.ray(px_right[i]));
    a[i] = S * rig.R * x[i];  // alpha2 a + b = 0 (paper Eq. 10 after [x'_d]x)
    b[i] = S * rig.T;
    if (a[i].squaredNorm() > 0.0) used.push_back(i);
  }
  if (used.empty()) return out;

  if (solve == DirectSolve::per_point) {
    for (std::size_t i : used) out.alpha2[i] = -a[i].dot(b[i]) / a[i].squaredNorm();
  } else {
    // Unknowns (alpha2_1 .. alpha2_m, 1): block i is [0 .. a_i .. 0 | b_i]. The right singular vector of
    // the smallest singular value, divided by its last entry, gives every alpha2 at once.
    const auto m = static_cast<Eigen::Index>(used.size());
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(3 * m, m + 1);
    for (Eigen::Index k = 0; k < m; ++k) {
      M.block<3, 1>(3 * k, k) = a[used[static_cast<std::size_t>(k)]];
      M.block<3, 1>(3 * k, m) = b[used[static_cast<std::size_t>(k)]];
    }
    const Eigen::BDCSVD<Eigen::MatrixXd> svd(M, Eigen::ComputeFullV);
    const Eigen::VectorXd v = svd.matrixV().col(m);
    if (!(std::abs(v(m)) > 1e-300)) return out;
    for (Eigen::Index k = 0; k < m; ++k) out.alpha2[used[static_cast<std::size_t>(k)]] = v(k) / v(m);
  }
  out.ok = true;
  for (std::size_t i : used) {
    const Eigen::Vector3d X = out.alpha2[i] * x[i];
    if (X.allFinite() && X.z() > 0.0 && (rig.R * X + rig.T).z() > 0.0) {
      out.points[i] = X;
      out.valid[i] = true;
    } else {
      out.alpha2[i] = nan;
    }
  }
  return out;
}

namespace {

Triangulated undistort_and_triangulate(const DivisionRig& rig, const StereoRig& pinhole,
                                       const Eigen::Vector2d& px_left, const Eigen::Vector2d& px_right,
                                       TriangulationMethod method, double corner_sigma_px) {
  const auto ul = rig.left.undistort_pixel(px_left);
  const auto ur = rig.right.undistort_pixel(px_right);
  Triangulated t;
  if (!ul || !ur) {
    t.status = ul ? TriangulationStatus::right_pixel_invalid : TriangulationStatus::left_pixel_invalid;
    t.left_undistort = ul ? UndistortStatus::ok : UndistortStatus::outside_model;
    t.right_undistort = ur ? UndistortStatus::ok : UndistortStatus::outside_model;
    return t;
  }
  // The pinhole rig undistorts trivially (zero distortion), so pixel-level triangulate() is exact here.
  return triangulate(pinhole, *ul, *ur, method, corner_sigma_px);
}

}  // namespace

Triangulated triangulate_undistorted(const DivisionRig& rig, const Eigen::Vector2d& px_left,
                                     const Eigen::Vector2d& px_right, TriangulationMethod method,
                                     double corner_sigma_px) {
  return undistort_and_triangulate(rig, rig.pinhole(), px_left, px_right, method, corner_sigma_px);
}

std::vector<Triangulated> triangulate_undistorted(const DivisionRig& rig,
                                                  std::span<const Eigen::Vector2d> px_left,
                                                  std::span<const Eigen::Vector2d> px_right,
                                                  TriangulationMethod method, double corner_sigma_px) {
  if (px_left.size() != px_right.size()) throw std::invalid_argument("triangulate_undistorted: sizes differ");
  const StereoRig pinhole = rig.pinhole();
  std::vector<Triangulated> out;
  out.reserve(px_left.size());
  for (std::size_t i = 0; i < px_left.size(); ++i) {
    out.push_back(undistort_and_triangulate(rig, pinhole, px_left[i], px_right[i], method, corner_sigma_px));
  }
  return out;
}

std::vector<Eigen::Vector3d> triangulated_points(std::span<const Triangulated> t) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(t.size());
  for (const auto& x : t) out.push_back(x.X);  // NaN unless ok()
  return out;
}

std::optional<double> division_reprojection_error(const DivisionRig& rig,
                                                  std::span<const Eigen::Vector3d> points,
                                                  std::span<const Eigen::Vector2d> px_left,
                                                  std::span<const Eigen::Vector2d> px_right) {
  if (points.size() != px_left.size() || points.size() != px_right.size()) {
    throw std::invalid_argument("division_reprojection_error: sizes differ");
  }
  double sum = 0;
  int count = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) continue;
    const auto l = rig.left.project(points[i]);
    const auto r = rig.right.project(rig.R * points[i] + rig.T);
    if (!l || !r) continue;
    sum += (*l - px_left[i]).norm() + (*r - px_right[i]).norm();
    count += 2;
  }
  if (count == 0) return std::nullopt;
  return sum / count;
}

}  // namespace naneye::recon
