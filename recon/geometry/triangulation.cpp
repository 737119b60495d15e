#include "naneye/recon/geometry/triangulation.hpp"
#include "naneye/base/enum_table.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace naneye::recon {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Eigen::Vector3d homogeneous(const Eigen::Vector2d& x) {
  return {x.x(), x.y(), 1.0};
}

// d(raw pixel)/d(X_cam) for one camera: K (2x2 part) * distortion Jacobian * d(x/z, y/z)/dX.
Eigen::Matrix<double, 2, 3> pixel_jacobian(const CameraModel& cam, const Eigen::Vector3d& Xc) {
  const double iz = 1.0 / Xc.z();
  const Eigen::Vector2d xn = Xc.head<2>() * iz;
  Eigen::Matrix<double, 2, 3> dxn;
  dxn << iz, 0.0, -xn.x() * iz, 0.0, iz, -xn.y() * iz;
  Eigen::Matrix2d K2;
  K2 << cam.fx(), cam.skew(), 0.0, cam.fy();
  return K2 * cam.distort_jacobian(xn) * dxn;
}

}  // namespace

namespace {
constexpr base::EnumTable<TriangulationMethod, 4> kTriangulationMethodNames{
    {{TriangulationMethod::dlt, "dlt"},
     {TriangulationMethod::midpoint, "midpoint"},
     {TriangulationMethod::niter2, "niter2"},
     {TriangulationMethod::refined, "refined"}}};
}  // namespace

const char* to_string(TriangulationMethod m) {
  return base::enum_name(kTriangulationMethodNames, m);
}

namespace {
constexpr base::EnumTable<TriangulationStatus, 5> kTriangulationStatusNames{
    {{TriangulationStatus::ok, "ok"},
     {TriangulationStatus::left_pixel_invalid, "left_pixel_invalid"},
     {TriangulationStatus::right_pixel_invalid, "right_pixel_invalid"},
     {TriangulationStatus::parallel_rays, "parallel_rays"},
     {TriangulationStatus::behind_camera, "behind_camera"}}};
}  // namespace

const char* to_string(TriangulationStatus s) {
  return base::enum_name(kTriangulationStatusNames, s);
}

Eigen::Vector3d triangulate_dlt(const StereoRig& rig, const Eigen::Vector2d& xl, const Eigen::Vector2d& xr) {
  // H&Z Sec. 12.2: x p3^T - p1^T and y p3^T - p2^T for each camera, stacked; X is the null vector.
  Eigen::Matrix<double, 3, 4> P2;
  P2 << rig.R, rig.T;
  Eigen::Matrix4d A;
  A << -1.0, 0.0, xl.x(), 0.0,  // P1 = [I|0]
      0.0, -1.0, xl.y(), 0.0,   //
      xr.x() * P2.row(2) - P2.row(0), xr.y() * P2.row(2) - P2.row(1);
  const Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d Xh = svd.matrixV().col(3);
  return Xh.head<3>() / Xh.w();
}

Eigen::Vector3d triangulate_midpoint(const StereoRig& rig, const Eigen::Vector2d& xl,
                                     const Eigen::Vector2d& xr) {
  // Rays s d1 (from the left centre, the origin) and C + t d2. The closest points have
  // s = det[C, d2, n] / |n|^2, t = det[C, d1, n] / |n|^2 with n = d1 x d2; the cross-product form
  // keeps precision for the nearly parallel rays of a 1 mm baseline (no a c - b^2 cancellation).
  const Eigen::Vector3d d1 = homogeneous(xl);
  const Eigen::Vector3d d2 = rig.R.transpose() * homogeneous(xr);
  const Eigen::Vector3d C = rig.right_center();
  const Eigen::Vector3d n = d1.cross(d2);
  const double nn = n.squaredNorm();
  if (!(nn > 0.0)) return Eigen::Vector3d::Constant(kNaN);
  const double s = C.cross(d2).dot(n) / nn;
  const double t = C.cross(d1).dot(n) / nn;
  return 0.5 * (s * d1 + C + t * d2);
}

CorrectedPair niter2_correct(const Eigen::Matrix3d& E, const Eigen::Vector2d& xl, const Eigen::Vector2d& xr) {
  // Lindstrom 2010, listing "niter2", written for his constraint x^T E x' = 0. Ours is
  // xr^T E xl = 0, so his x is our xr and his x' our xl: n_r = S E xl is the gradient of the
  // constraint with respect to xr, n_l = S E^T xr the one with respect to xl.
  const Eigen::Vector3d hl = homogeneous(xl), hr = homogeneous(xr);
  const Eigen::Matrix2d Et = E.topLeftCorner<2, 2>();
  Eigen::Vector2d n_r = (E * hl).head<2>();
  Eigen::Vector2d n_l = (E.transpose() * hr).head<2>();
  const double a = n_r.dot(Et * n_l);
  const double b = 0.5 * (n_r.squaredNorm() + n_l.squaredNorm());
  const double c = hr.dot(E * hl);
  const double d = std::sqrt(std::max(0.0, b * b - a * c));
  double lambda = c / (b + d);
  const Eigen::Vector2d dl = lambda * n_l, dr = lambda * n_r;
  n_r -= Et * dl;
  n_l -= Et.transpose() * dr;
  lambda *= 2.0 * d / (n_r.squaredNorm() + n_l.squaredNorm());
  return {xl - lambda * n_l, xr - lambda * n_r};
}

Eigen::Vector3d intersect_corrected(const StereoRig& rig, const CorrectedPair& c) {
  // xr ~ R z xl + T  =>  z (xr x R xl) = -(xr x T); least squares in z.
  const Eigen::Vector3d hl = homogeneous(c.xl), hr = homogeneous(c.xr);
  const Eigen::Vector3d a = hr.cross(rig.R * hl);
  const Eigen::Vector3d b = hr.cross(rig.T);
  const double aa = a.squaredNorm();
  if (!(aa > 0.0)) return Eigen::Vector3d::Constant(kNaN);
  return (-a.dot(b) / aa) * hl;
}

Eigen::Vector3d triangulate_niter2(const StereoRig& rig, const Eigen::Vector2d& xl,
                                   const Eigen::Vector2d& xr) {
  return intersect_corrected(rig, niter2_correct(rig.essential(), xl, xr));
}

Eigen::Vector4d reprojection_residual(const StereoRig& rig, const Eigen::Vector3d& X,
                                      const Eigen::Vector2d& px_left, const Eigen::Vector2d& px_right) {
  Eigen::Vector4d r;
  r.head<2>() = rig.left.project(X) - px_left;
  r.tail<2>() = rig.right.project(rig.R * X + rig.T) - px_right;
  return r;
}

Eigen::Matrix<double, 4, 3> reprojection_jacobian(const StereoRig& rig, const Eigen::Vector3d& X) {
  Eigen::Matrix<double, 4, 3> J;
  J.topRows<2>() = pixel_jacobian(rig.left, X);
  J.bottomRows<2>() = pixel_jacobian(rig.right, rig.R * X + rig.T) * rig.R;
  return J;
}

Eigen::Vector3d refine_reprojection(const StereoRig& rig, const Eigen::Vector3d& X0,
                                    const Eigen::Vector2d& px_left, const Eigen::Vector2d& px_right,
                                    int max_iterations) {
  // Gauss-Newton; from the niter2 point it is in the quadratic basin and takes 1-3 steps. A step
  // that raises the cost (nearly parallel rays, where J^T J is close to singular along the depth)
  // is retried with Levenberg-Marquardt damping mu diag(J^T J) instead of giving up.
  Eigen::Vector3d X = X0;
  Eigen::Vector4d r = reprojection_residual(rig, X, px_left, px_right);
  double cost = r.squaredNorm();
  double mu = 0.0;
  for (int it = 0; it < max_iterations; ++it) {
    const Eigen::Matrix<double, 4, 3> J = reprojection_jacobian(rig, X);
    const Eigen::Matrix3d H = J.transpose() * J;
    const Eigen::Vector3d g = J.transpose() * r;
    bool accepted = false;
    Eigen::Vector3d step = Eigen::Vector3d::Zero();
    for (int attempt = 0; attempt < 8 && !accepted; ++attempt) {
      Eigen::Matrix3d A = H;
      A.diagonal() *= 1.0 + mu;
      step = A.ldlt().solve(-g);
      // A step below 1e-12 of the point's own size is the residual's rounding (a pixel's double
      // carries ~2e-14 px): converged. Evaluating it only set off the damped retries below, which
      // cannot gain anything either (measured on a sparse scene pair: 2 600 of 6 400 solves).
      if (step.allFinite() && step.norm() <= 1e-12 * X.norm()) return X;
      const Eigen::Vector3d cand = X + step;
      if (step.allFinite() && cand.z() > 0.0) {
        const Eigen::Vector4d cand_r = reprojection_residual(rig, cand, px_left, px_right);
        const double cand_cost = cand_r.squaredNorm();
        if (cand_cost <= cost) {
          X = cand;
          r = cand_r;
          accepted = cand_cost < cost;
          cost = cand_cost;
          if (!accepted) return X;  // no change to rounding: converged
          break;
        }
      }
      mu = mu == 0.0 ? 1e-4 : 10.0 * mu;
    }
    if (!accepted) break;
    mu *= 0.1;
  }
  return X;
}

Eigen::Matrix3d point_covariance(const StereoRig& rig, const Eigen::Vector3d& X, double corner_sigma_px) {
  // Sigma_X = sigma^2 (J^T J)^-1 (H&Z 2nd ed. Sec. 5.2): the ML point's covariance when the four
  // raw-pixel coordinates carry independent N(0, sigma^2) noise, to first order.
  const Eigen::Matrix<double, 4, 3> J = reprojection_jacobian(rig, X);
  return corner_sigma_px * corner_sigma_px * (J.transpose() * J).inverse();
}

double depth_sigma_mm(const StereoRig& rig, const Eigen::Vector3d& X, double corner_sigma_px) {
  return std::sqrt(point_covariance(rig, X, corner_sigma_px)(2, 2));
}

Triangulated triangulate(const StereoRig& rig, const StereoObservation& obs, TriangulationMethod method,
                         double corner_sigma_px) {
  Triangulated out;
  Eigen::Vector3d X;
  switch (method) {
    case TriangulationMethod::dlt:
      X = triangulate_dlt(rig, obs.xn_left, obs.xn_right);
      break;
    case TriangulationMethod::midpoint:
      X = triangulate_midpoint(rig, obs.xn_left, obs.xn_right);
      break;
    case TriangulationMethod::niter2:
      X = triangulate_niter2(rig, obs.xn_left, obs.xn_right);
      break;
    case TriangulationMethod::refined:
      X = triangulate_niter2(rig, obs.xn_left, obs.xn_right);
      if (X.allFinite() && X.z() > 0.0) X = refine_reprojection(rig, X, obs.px_left, obs.px_right);
      break;
  }
  if (!X.allFinite()) {
    out.status = TriangulationStatus::parallel_rays;
    return out;
  }
  if (!(X.z() > 0.0) || !((rig.R.row(2).dot(X) + rig.T.z()) > 0.0)) {
    out.status = TriangulationStatus::behind_camera;
    return out;
  }
  out.status = TriangulationStatus::ok;
  out.X = X;
  out.depth_sigma_mm = depth_sigma_mm(rig, X, corner_sigma_px);
  return out;
}

Triangulated triangulate(const StereoRig& rig, const Eigen::Vector2d& px_left,
                         const Eigen::Vector2d& px_right, TriangulationMethod method,
                         double corner_sigma_px) {
  // Both sides are undistorted so that a refused pair reports why for each of them.
  Triangulated out;
  const Undistorted ul = rig.left.undistort(px_left);
  const Undistorted ur = rig.right.undistort(px_right);
  out.left_undistort = ul.status;
  out.right_undistort = ur.status;
  if (!ul.ok()) {
    out.status = TriangulationStatus::left_pixel_invalid;
    return out;
  }
  if (!ur.ok()) {
    out.status = TriangulationStatus::right_pixel_invalid;
    return out;
  }
  Triangulated t = triangulate(rig, StereoObservation{px_left, px_right, ul.normalized, ur.normalized},
                               method, corner_sigma_px);
  t.left_undistort = ul.status;
  t.right_undistort = ur.status;
  return t;
}

}  // namespace naneye::recon
