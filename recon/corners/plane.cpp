#include "plane.hpp"

#include <Eigen/Eigenvalues>
#include <array>
#include <cmath>

namespace naneye::recon {
namespace {
// Hartley's normalisation: centroid to the origin, mean distance sqrt(2).
bool normaliser(const std::array<Eigen::Vector2d, kMaxCorners>& p, int n, Eigen::Matrix3d& T) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (int i = 0; i < n; ++i) mean += p[static_cast<std::size_t>(i)];
  mean /= n;
  double spread = 0;
  for (int i = 0; i < n; ++i) spread += (p[static_cast<std::size_t>(i)] - mean).norm();
  spread /= n;
  if (!(spread > 0)) return false;
  const double s = std::sqrt(2.0) / spread;
  T << s, 0, -s * mean.x(), 0, s, -s * mean.y(), 0, 0, 1;
  return true;
}
}  // namespace

bool grid_plane_residual(const CornerResult& r, const CameraModel& cam, double& rms_px, double& worst_px) {
  std::array<Eigen::Vector2d, kMaxCorners> xs, bs;
  int n = 0;
  for (int i = 0; i < r.count; ++i) {
    const Corner& c = r.corners[static_cast<std::size_t>(i)];
    if (c.flags & kCornerBeyondFold) continue;
    const Undistorted u = cam.undistort(c.px);
    if (!u.ok()) continue;
    xs[static_cast<std::size_t>(n)] = u.normalized * cam.fx();
    bs[static_cast<std::size_t>(n)] = {c.col, c.row};
    ++n;
  }
  if (n < 8) return false;
  Eigen::Matrix3d Tx, Tb;
  if (!normaliser(xs, n, Tx) || !normaliser(bs, n, Tb)) return false;
  // A^T A of the DLT rows accumulated directly (9 x 9): its smallest eigenvector is h.
  Eigen::Matrix<double, 9, 9> AtA = Eigen::Matrix<double, 9, 9>::Zero();
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const Eigen::Vector3d b = Tb * Eigen::Vector3d(bs[k].x(), bs[k].y(), 1.0);
    const Eigen::Vector3d x = Tx * Eigen::Vector3d(xs[k].x(), xs[k].y(), 1.0);
    Eigen::Matrix<double, 9, 1> r1, r2;
    r1 << b, Eigen::Vector3d::Zero(), -x.x() * b;
    r2 << Eigen::Vector3d::Zero(), b, -x.y() * b;
    AtA.selfadjointView<Eigen::Lower>().rankUpdate(r1);
    AtA.selfadjointView<Eigen::Lower>().rankUpdate(r2);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> es(AtA);  // reads the lower half
  if (es.info() != Eigen::Success) return false;
  const Eigen::Matrix<double, 9, 1> h = es.eigenvectors().col(0);  // eigenvalues ascending
  Eigen::Matrix3d Hn;
  Hn << h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8];
  const Eigen::Matrix3d H = Tx.inverse() * Hn * Tb;
  double sum = 0;
  worst_px = 0;
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const Eigen::Vector3d p = H * Eigen::Vector3d(bs[k].x(), bs[k].y(), 1.0);
    if (std::abs(p.z()) < 1e-12) return false;
    const double e = (p.head<2>() / p.z() - xs[k]).norm();
    sum += e * e;
    worst_px = std::max(worst_px, e);
  }
  // The algebraic fit is not the geometric optimum; with 48 corners and sub-pixel noise the
  // difference is far below the thresholds this is compared with.
  rms_px = std::sqrt(sum / n);
  return true;
}

}  // namespace naneye::recon
