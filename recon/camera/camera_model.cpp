#include "naneye/recon/camera/camera_model.hpp"
#include "naneye/base/enum_table.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace naneye::recon {

namespace {
constexpr base::EnumTable<UndistortStatus, 3> kUndistortStatusNames{
    {{UndistortStatus::ok, "ok"},
     {UndistortStatus::outside_model, "outside_model"},
     {UndistortStatus::no_convergence, "no_convergence"}}};
}  // namespace

const char* to_string(UndistortStatus s) {
  return base::enum_name(kUndistortStatusNames, s);
}

std::optional<double> radial_fold_radius(double k1, double k2, double k3) {
  // d/dr [r f(r^2)] = 1 + 3 k1 s + 5 k2 s^2 + 7 k3 s^3 with s = r^2. Its value at s = 0 is 1, so the
  // first sign change on s > 0 is the fold. Bracket it by scanning (the polynomial is at most cubic,
  // so a fine scan cannot step over two roots unnoticed unless they are closer than the step, in which
  // case the derivative never goes negative between them and there is no fold there), then bisect.
  auto g = [&](double s) { return 1.0 + s * (3.0 * k1 + s * (5.0 * k2 + s * 7.0 * k3)); };
  // Beyond r = 10 (normalized; 84 degrees off-axis) no lens of this kind is modelled.
  const double s_max = 100.0;
  const int steps = 20000;
  double prev_s = 0.0;
  for (int i = 1; i <= steps; ++i) {
    const double s = s_max * i / steps;
    if (g(s) <= 0.0) {
      double lo = prev_s, hi = s;
      for (int it = 0; it < 200 && hi - lo > 0.0; ++it) {
        const double mid = 0.5 * (lo + hi);
        if (mid <= lo || mid >= hi) break;
        (g(mid) > 0.0 ? lo : hi) = mid;
      }
      return std::sqrt(lo);
    }
    prev_s = s;
  }
  return std::nullopt;
}

CameraModel::CameraModel(const Eigen::Matrix3d& K, const Distortion& d, int width, int height)
    : K_(K), d_(d), width_(width), height_(height) {
  if (!(K(0, 0) > 0.0) || !(K(1, 1) > 0.0) || K(1, 0) != 0.0 || K(2, 0) != 0.0 || K(2, 1) != 0.0 ||
      K(2, 2) != 1.0) {
    throw std::invalid_argument("camera matrix must be [fx s cx; 0 fy cy; 0 0 1] with fx, fy > 0");
  }
  fold_r_ = radial_fold_radius(d.k1, d.k2, d.k3);
  if (fold_r_) {
    const double r = *fold_r_, s = r * r;
    fold_rd_ = r * (1.0 + s * (d.k1 + s * (d.k2 + s * d.k3)));
  }
}

std::optional<double> CameraModel::fold_radius_px() const {
  if (!fold_rd_) return std::nullopt;
  return *fold_rd_ * fx();
}

Eigen::Matrix2d CameraModel::distort_jacobian(const Eigen::Vector2d& xn) const {
  const double x = xn.x(), y = xn.y();
  const double r2 = x * x + y * y;
  const double f = 1.0 + r2 * (d_.k1 + r2 * (d_.k2 + r2 * d_.k3));
  const double df = d_.k1 + r2 * (2.0 * d_.k2 + r2 * 3.0 * d_.k3);  // d f / d(r^2)
  Eigen::Matrix2d J;
  J(0, 0) = f + 2.0 * x * x * df + 2.0 * d_.p1 * y + 6.0 * d_.p2 * x;
  J(0, 1) = 2.0 * x * y * df + 2.0 * d_.p1 * x + 2.0 * d_.p2 * y;
  J(1, 0) = 2.0 * x * y * df + 2.0 * d_.p1 * x + 2.0 * d_.p2 * y;
  J(1, 1) = f + 2.0 * y * y * df + 6.0 * d_.p1 * y + 2.0 * d_.p2 * x;
  return J;
}

Eigen::Vector2d CameraModel::from_pixel(const Eigen::Vector2d& px) const {
  const double yd = (px.y() - cy()) / fy();
  return {(px.x() - cx() - skew() * yd) / fx(), yd};
}

void CameraModel::project_rays_at(const double* rx, const double* ry, const double* rz, double z,
                                  const Eigen::Vector3d& t, int n, Eigen::Vector2d* out) const {
  // distort() and to_pixel() written out on two lanes, operation for operation in their order (no
  // FMA on x86-64's baseline: each lane rounds as the scalar code does).
  using D2 = double __attribute__((vector_size(16)));
  int j = 0;
  for (; !d_.has_tangential() && j + 2 <= n; j += 2) {
    const D2 X = D2{rx[j], rx[j + 1]} * z + t.x(), Y = D2{ry[j], ry[j + 1]} * z + t.y(),
             Z = D2{rz[j], rz[j + 1]} * z + t.z();
    const D2 x = X / Z, y = Y / Z;
    const D2 r2 = x * x + y * y;
    const D2 radial = 1.0 + r2 * (d_.k1 + r2 * (d_.k2 + r2 * d_.k3));
    const D2 xd = x * radial, yd = y * radial;
    const D2 u = fx() * xd + skew() * yd + cx(), v = fy() * yd + cy();
    out[j] = Eigen::Vector2d(u[0], v[0]);
    out[j + 1] = Eigen::Vector2d(u[1], v[1]);
  }
  for (; j < n; ++j)
    out[j] = project(Eigen::Vector3d(rx[j] * z + t.x(), ry[j] * z + t.y(), rz[j] * z + t.z()));
}

Eigen::Vector2d CameraModel::project(const Eigen::Vector3d& X, Eigen::Matrix<double, 2, 3>& J) const {
  const double iz = 1.0 / X.z();
  const Eigen::Vector2d xn = X.head<2>() * iz;
  Eigen::Matrix<double, 2, 3> dn;
  dn << iz, 0.0, -xn.x() * iz, 0.0, iz, -xn.y() * iz;
  Eigen::Matrix2d Kp;
  Kp << fx(), skew(), 0.0, fy();
  J = Kp * distort_jacobian(xn) * dn;
  return to_pixel(distort(xn));
}

Undistorted CameraModel::undistort(const Eigen::Vector2d& px) const {
  return undistort_distorted(from_pixel(px));
}

Undistorted CameraModel::undistort_distorted(const Eigen::Vector2d& xd) const {
  if (!std::isfinite(xd.x()) || !std::isfinite(xd.y())) return {};
  return d_.has_tangential() ? undistort_general(xd) : undistort_radial(xd);
}

// Radial-only model: the map is x_d = x_n f(r^2), so x_n is parallel to x_d and only the radius is
// unknown. Solve g(r) = r f(r^2) - r_d = 0 on [0, r_fold], where g increases strictly (the fold is the
// first zero of g'); Newton with the analytic derivative, kept inside a shrinking bracket so that it
// converges from any start, even next to the fold where g' -> 0.
Undistorted CameraModel::undistort_radial(const Eigen::Vector2d& xd) const {
  const double rd = xd.norm();
  Undistorted out;
  if (rd == 0.0) {
    out.status = UndistortStatus::ok;
    out.normalized = xd;
    return out;
  }
  if (fold_rd_ && rd >= *fold_rd_) return out;  // outside_model
  const double k1 = d_.k1, k2 = d_.k2, k3 = d_.k3;
  double lo = 0.0;
  double hi = fold_r_ ? *fold_r_ : std::numeric_limits<double>::infinity();
  double r = std::min(rd, fold_r_ ? 0.5 * (*fold_r_) + 0.5 * rd : rd);
  if (r >= hi) r = 0.5 * hi;
  int it = 0;
  for (; it < 100; ++it) {
    const double s = r * r;
    const double g = r * (1.0 + s * (k1 + s * (k2 + s * k3))) - rd;
    if (g == 0.0) break;
    (g < 0.0 ? lo : hi) = r;
    const double dg = 1.0 + s * (3.0 * k1 + s * (5.0 * k2 + s * 7.0 * k3));
    double next = r - g / dg;
    if (!(next > lo && next < hi)) {
      // Newton left the bracket: bisect instead (an unbounded bracket only arises without a fold,
      // where g grows at least linearly, so doubling finds an upper end).
      next = std::isfinite(hi) ? 0.5 * (lo + hi) : 2.0 * r;
    }
    if (std::abs(next - r) <= 4.0 * std::numeric_limits<double>::epsilon() * r) {
      r = next;
      break;
    }
    r = next;
  }
  if (!std::isfinite(r) || (fold_r_ && r >= *fold_r_)) return out;
  out.status = UndistortStatus::ok;
  out.normalized = xd * (r / rd);
  out.iterations = it + 1;
  return out;
}

// With tangential terms: 2-D Newton on distort(x) - x_d = 0 with the analytic Jacobian and a
// backtracking line search; the solution must lie inside the fold along its own direction.
Undistorted CameraModel::undistort_general(const Eigen::Vector2d& xd) const {
  Undistorted out;
  Eigen::Vector2d x = xd;
  Eigen::Vector2d res = distort(x) - xd;
  double cost = res.squaredNorm();
  for (int it = 0; it < 60; ++it) {
    if (cost <= 1e-32) {
      out.iterations = it;
      break;
    }
    const Eigen::Matrix2d J = distort_jacobian(x);
    const double det = J.determinant();
    if (!(det > 0.0)) return out;  // crossed the fold
    Eigen::Vector2d step = J.inverse() * res;
    double t = 1.0;
    bool improved = false;
    for (int ls = 0; ls < 30; ++ls, t *= 0.5) {
      const Eigen::Vector2d cand = x - t * step;
      const Eigen::Vector2d cand_res = distort(cand) - xd;
      if (cand_res.squaredNorm() < cost) {
        x = cand;
        res = cand_res;
        cost = cand_res.squaredNorm();
        improved = true;
        break;
      }
    }
    out.iterations = it + 1;
    if (!improved) break;
  }
  // Tolerance: 1e-12 in normalized units is 2e-10 px at f = 216 px.
  if (!(cost <= 1e-24)) {
    out.status = UndistortStatus::no_convergence;
    return out;
  }
  if (!inside_fold_general(x)) {
    out.status = UndistortStatus::outside_model;
    return out;
  }
  out.status = UndistortStatus::ok;
  out.normalized = x;
  return out;
}

// The domain with tangential terms: the distortion Jacobian must stay positive-definite-in-determinant
// along the ray from the centre to the point (the region connected to the centre where the map is
// locally invertible).
bool CameraModel::inside_fold_general(const Eigen::Vector2d& xn) const {
  const int samples = 256;
  for (int i = 1; i <= samples; ++i) {
    const Eigen::Vector2d p = xn * (static_cast<double>(i) / samples);
    if (!(distort_jacobian(p).determinant() > 0.0)) return false;
  }
  return true;
}

}  // namespace naneye::recon
