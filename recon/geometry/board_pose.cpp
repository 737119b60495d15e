#include "naneye/recon/geometry/board_pose.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <vector>

namespace naneye::recon {
namespace {

struct Normal6 {
  Eigen::Matrix<double, 6, 6> JtJ = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> Jtr = Eigen::Matrix<double, 6, 1>::Zero();
  double cost = 0;
  int residuals = 0;
  bool valid = true;
};

// Residuals pixel(model) - pixel(measured) of every usable observation, in both eyes, and the normal
// equations of the left-multiplied increment (d_omega, d_t): X' = exp([d_omega]x) R P + t + d_t, so
// dX/d_omega = -[R P]x and dX/dt = I.
Normal6 accumulate(const StereoRig& rig, const BoardGeometry& board, std::span<const CornerObservation> obs,
                   const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Normal6 n;
  Eigen::Matrix<double, 2, 3> Jp;
  Eigen::Matrix<double, 3, 6> dX;
  for (const auto& o : obs) {
    const Eigen::Vector3d RP = R * board.corner(o.row, o.col);
    const Eigen::Vector3d Xl = RP + t;
    dX.leftCols<3>() = -skew(RP);
    dX.rightCols<3>().setIdentity();
    auto add = [&](const CameraModel& cam, const Eigen::Vector3d& X, const Eigen::Matrix3d& rot,
                   const Eigen::Vector2d& measured) {
      if (!(X.z() > 0.0)) {
        n.valid = false;
        return;
      }
      const Eigen::Vector2d r = cam.project(X, Jp) - measured;
      const Eigen::Matrix<double, 2, 6> J = Jp * rot * dX;
      n.JtJ.noalias() += J.transpose() * J;
      n.Jtr.noalias() += J.transpose() * r;
      n.cost += r.squaredNorm();
      n.residuals += 2;
    };
    if (o.left_ok) add(rig.left, Xl, Eigen::Matrix3d::Identity(), o.left_px);
    if (o.right_ok) add(rig.right, rig.R * Xl + rig.T, rig.R, o.right_px);
  }
  return n;
}

// The pose of the board plane from one eye's exactly undistorted points, without allocating: the
// normalized DLT homography board -> normalized image (Hartley & Zisserman, Alg. 4.2; the 9 x 9 normal
// matrix is fixed-size) decomposed as H ~ [r1 r2 t] (Zhang 2000, Sec. 3.1), R made orthonormal by SVD.
// The LM below polishes it; IPPE (cv::solvePnP, which allocates) is the fallback when this fails.
bool homography_pose(const CameraModel& cam, const BoardGeometry& board,
                     std::span<const CornerObservation> obs, bool use_left, Eigen::Matrix3d& R,
                     Eigen::Vector3d& t) {
  // Two passes: centroids and scales first (Hartley's normalization), then the normal matrix.
  Eigen::Vector2d cb = Eigen::Vector2d::Zero(), ci = Eigen::Vector2d::Zero();
  int n = 0;
  auto each = [&](auto&& f) {
    for (const auto& o : obs) {
      if (!(use_left ? o.left_ok : o.right_ok)) continue;
      const Undistorted u = cam.undistort(use_left ? o.left_px : o.right_px);
      if (!u.ok()) continue;
      f(board.corner(o.row, o.col).head<2>(), u.normalized);
    }
  };
  each([&](const Eigen::Vector2d& b, const Eigen::Vector2d& x) {
    cb += b;
    ci += x;
    ++n;
  });
  if (n < 4) return false;
  cb /= n;
  ci /= n;
  double db = 0, di = 0;
  each([&](const Eigen::Vector2d& b, const Eigen::Vector2d& x) {
    db += (b - cb).norm();
    di += (x - ci).norm();
  });
  if (!(db > 0) || !(di > 0)) return false;
  const double sb = std::sqrt(2.0) * n / db, si = std::sqrt(2.0) * n / di;
  Eigen::Matrix<double, 9, 9> M = Eigen::Matrix<double, 9, 9>::Zero();
  each([&](const Eigen::Vector2d& b, const Eigen::Vector2d& x) {
    const Eigen::Vector2d B = sb * (b - cb), X = si * (x - ci);
    Eigen::Matrix<double, 9, 1> r1, r2;
    r1 << B.x(), B.y(), 1, 0, 0, 0, -X.x() * B.x(), -X.x() * B.y(), -X.x();
    r2 << 0, 0, 0, B.x(), B.y(), 1, -X.y() * B.x(), -X.y() * B.y(), -X.y();
    M.noalias() += r1 * r1.transpose() + r2 * r2.transpose();
  });
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> eig(M);
  if (eig.info() != Eigen::Success) return false;
  const Eigen::Matrix<double, 9, 1> h = eig.eigenvectors().col(0);
  Eigen::Matrix3d Hn;
  Hn << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), h(8);
  Eigen::Matrix3d Tb, Ti_inv;
  Tb << sb, 0, -sb * cb.x(), 0, sb, -sb * cb.y(), 0, 0, 1;
  Ti_inv << 1 / si, 0, ci.x(), 0, 1 / si, ci.y(), 0, 0, 1;
  const Eigen::Matrix3d H = Ti_inv * Hn * Tb;
  double lambda = 2.0 / (H.col(0).norm() + H.col(1).norm());
  if (!std::isfinite(lambda)) return false;
  if (H(2, 2) * lambda < 0) lambda = -lambda;  // the board in front of the camera
  Eigen::Matrix3d Rh;
  Rh.col(0) = lambda * H.col(0);
  Rh.col(1) = lambda * H.col(1);
  Rh.col(2) = Rh.col(0).cross(Rh.col(1));
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(Rh, Eigen::ComputeFullU | Eigen::ComputeFullV);
  R = svd.matrixU() * svd.matrixV().transpose();
  if (R.determinant() < 0) return false;
  t = lambda * H.col(2);
  return t.allFinite() && t.z() > 0.0;
}

// Planar PnP (IPPE) on the exactly undistorted points of one eye. Returns false with < 4 points.
bool initial_pose(const CameraModel& cam, const BoardGeometry& board, std::span<const CornerObservation> obs,
                  bool use_left, Eigen::Matrix3d& R, Eigen::Vector3d& t) {
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (const auto& o : obs) {
    if (!(use_left ? o.left_ok : o.right_ok)) continue;
    const Undistorted u = cam.undistort(use_left ? o.left_px : o.right_px);
    if (!u.ok()) continue;
    const Eigen::Vector3d P = board.corner(o.row, o.col);
    object.emplace_back(P.x(), P.y(), P.z());
    image.emplace_back(u.normalized.x(), u.normalized.y());
  }
  if (object.size() < 4) return false;
  cv::Mat rvec, tvec;
  if (!cv::solvePnP(object, image, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), rvec, tvec, false,
                    cv::SOLVEPNP_IPPE))
    return false;
  Eigen::Vector3d om;
  cv::cv2eigen(rvec, om);
  cv::cv2eigen(tvec, t);
  R = rodrigues(om);
  return t.z() > 0.0;
}

}  // namespace

Eigen::Vector3d BoardPose::normal() const {
  Eigen::Vector3d n = R.col(2);
  return n.dot(t) > 0.0 ? -n : n;  // the camera centre (origin) is on the side n points to
}

double BoardPose::plane_distance_mm() const {
  return std::abs(R.col(2).dot(t));
}

BoardPose estimate_board_pose(const StereoRig& rig, const BoardGeometry& board,
                              std::span<const CornerObservation> obs, double corner_sigma_px) {
  BoardPose pose;
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  if (!homography_pose(rig.left, board, obs, true, R, t) && !initial_pose(rig.left, board, obs, true, R, t)) {
    Eigen::Matrix3d Rr;
    Eigen::Vector3d tr;
    if (!homography_pose(rig.right, board, obs, false, Rr, tr) &&
        !initial_pose(rig.right, board, obs, false, Rr, tr))
      return pose;
    R = rig.R.transpose() * Rr;  // X_r = Rr P + tr = R_rig (R P + t) + T
    t = rig.R.transpose() * (tr - rig.T);
  }

  // Levenberg-Marquardt damping keeps the rare bad start from diverging; near the optimum it is plain
  // Gauss-Newton.
  Normal6 n = accumulate(rig, board, obs, R, t);
  if (!n.valid || n.residuals < 6) return pose;
  double lambda = 1e-6;
  int it = 0;
  for (; it < 30; ++it) {
    Eigen::Matrix<double, 6, 6> A = n.JtJ;
    A.diagonal() *= 1.0 + lambda;
    const Eigen::Matrix<double, 6, 1> step = -A.ldlt().solve(n.Jtr);
    const Eigen::Matrix3d R_new = rodrigues(Eigen::Vector3d(step.head<3>())) * R;
    const Eigen::Vector3d t_new = t + step.tail<3>();
    const Normal6 cand = accumulate(rig, board, obs, R_new, t_new);
    if (cand.valid && cand.cost <= n.cost) {
      R = R_new;
      t = t_new;
      const bool converged = n.cost - cand.cost <= 1e-14 * (1.0 + n.cost) || step.norm() < 1e-12;
      n = cand;
      lambda = std::max(lambda * 0.1, 1e-9);
      if (converged) break;
    } else {
      lambda *= 10.0;
      if (lambda > 1e6) break;
    }
  }
  const Eigen::FullPivLU<Eigen::Matrix<double, 6, 6>> lu(n.JtJ);
  if (!lu.isInvertible()) return pose;
  pose.ok = true;
  pose.R = R;
  pose.t = t;
  pose.residuals = n.residuals;
  pose.rms_px = std::sqrt(n.cost / (n.residuals / 2));
  pose.iterations = it + 1;
  pose.covariance = corner_sigma_px * corner_sigma_px * lu.inverse();
  return pose;
}

std::optional<RayHit> intersect_board(const StereoRig& rig, const BoardPose& pose,
                                      const Eigen::Vector2d& left_px) {
  if (!pose.ok) return std::nullopt;
  const Undistorted u = rig.left.undistort(left_px);
  if (!u.ok()) return std::nullopt;
  const Eigen::Vector3d d(u.normalized.x(), u.normalized.y(), 1.0);
  const Eigen::Vector3d n = pose.R.col(2);
  const double N = n.dot(pose.t), D = n.dot(d);
  if (D == 0.0) return std::nullopt;
  const double Z = N / D;  // d.z() == 1, so the ray parameter is the depth
  if (!(Z > 0.0)) return std::nullopt;
  // Z(d_omega, d_t) = (n' . (t + d_t)) / (n' . d) with n' = n + d_omega x n, so
  // dZ/dt = n / D and dZ/d_omega = (n x t) / D - N (n x d) / D^2.
  Eigen::Matrix<double, 6, 1> g;
  g.head<3>() = n.cross(pose.t) / D - N * n.cross(d) / (D * D);
  g.tail<3>() = n / D;
  RayHit hit;
  hit.point = Z * d;
  hit.depth_mm = Z;
  hit.depth_sigma_mm = std::sqrt(std::max(0.0, g.dot(pose.covariance * g)));
  return hit;
}

}  // namespace naneye::recon
