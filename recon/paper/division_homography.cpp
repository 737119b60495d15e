#include "naneye/recon/paper/division_homography.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "naneye/base/median.hpp"
#include "naneye/recon/paper/division_model.hpp"

namespace naneye::recon {
namespace {

constexpr double kNoImage = 1e3;

Eigen::Vector3d lifted(const Eigen::Vector2d& x, double lambda) {
  return {x.x(), x.y(), 1.0 + lambda * x.squaredNorm()};
}

// Distorted image of the homogeneous undistorted point p, or empty (at infinity, or no real root).
std::optional<Eigen::Vector2d> distort_h(const Eigen::Vector3d& p, double lambda) {
  if (!(std::abs(p.z()) > 1e-300)) return std::nullopt;
  const Eigen::Vector2d u = p.head<2>() / p.z();
  const double ru = u.norm();
  if (!std::isfinite(ru)) return std::nullopt;
  if (ru == 0.0) return u;
  const auto rd = division_distort_radius(lambda, ru);
  if (!rd) return std::nullopt;
  return u * (*rd / ru);
}

void transfer(const Eigen::Matrix3d& H, const Eigen::Matrix3d& Hi, double lam, double lamr,
              std::span<const Eigen::Vector2d> l, std::span<const Eigen::Vector2d> r, double* out) {
  for (std::size_t i = 0; i < l.size(); ++i, out += 4) {
    const auto fwd = distort_h(H * lifted(l[i], lam), lamr);
    const auto bwd = distort_h(Hi * lifted(r[i], lamr), lam);
    const Eigen::Vector2d ef = fwd ? Eigen::Vector2d(*fwd - r[i]) : Eigen::Vector2d(kNoImage, kNoImage);
    const Eigen::Vector2d eb = bwd ? Eigen::Vector2d(*bwd - l[i]) : Eigen::Vector2d(kNoImage, kNoImage);
    out[0] = ef.x();
    out[1] = ef.y();
    out[2] = eb.x();
    out[3] = eb.y();
  }
}

// Kukelova et al. 2015, non-minimal: third row of Eq. 9 -> (h1, h2, lambda), rows one and two ->
// (h3, lambda'). Coordinates are already conditioned (radii ~ 1).
bool linear_solve(std::span<const Eigen::Vector2d> l, std::span<const Eigen::Vector2d> r, Eigen::Matrix3d& H,
                  double& lam, double& lamr) {
  const auto n = static_cast<Eigen::Index>(l.size());
  if (n < 8) return false;
  Eigen::MatrixXd M(n, 8);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double x = l[i].x(), y = l[i].y(), xp = r[i].x(), yp = r[i].y(), r2 = l[i].squaredNorm();
    M.row(i) << -yp * x, -yp * y, -yp, xp * x, xp * y, xp, -yp * r2, xp * r2;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(M, Eigen::ComputeFullV);
  const Eigen::Matrix<double, 8, 1> v = svd.matrixV().col(7);
  const double denom = v(2) * v(2) + v(5) * v(5);
  // h13 = h23 = 0 (no translation in the image plane) leaves lambda unobservable from this row.
  if (!(denom > 1e-24)) return false;
  lam = (v(6) * v(2) + v(7) * v(5)) / denom;
  H.row(0) = v.segment<3>(0).transpose();
  H.row(1) = v.segment<3>(3).transpose();

  Eigen::MatrixXd B(2 * n, 4);
  Eigen::VectorXd c(2 * n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d p = lifted(l[i], lam);
    const double a1 = H.row(0).dot(p), a2 = H.row(1).dot(p);
    const double xp = r[i].x(), yp = r[i].y(), rp2 = r[i].squaredNorm();
    B.row(2 * i) << yp * p.x(), yp * p.y(), yp * p.z(), -rp2 * a2;
    c(2 * i) = a2;
    B.row(2 * i + 1) << -xp * p.x(), -xp * p.y(), -xp * p.z(), rp2 * a1;
    c(2 * i + 1) = -a1;
  }
  const Eigen::Vector4d u = B.colPivHouseholderQr().solve(c);
  H.row(2) = u.head<3>().transpose();
  lamr = u(3);
  return H.allFinite() && std::isfinite(lam) && std::isfinite(lamr);
}

// H with both lambdas known: the lifted points are ordinary homogeneous points, plain DLT.
Eigen::Matrix3d dlt_fixed_lambda(std::span<const Eigen::Vector2d> l, std::span<const Eigen::Vector2d> r,
                                 double lam, double lamr) {
  const auto n = static_cast<Eigen::Index>(l.size());
  Eigen::MatrixXd M(2 * n, 9);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::RowVector3d p = lifted(l[i], lam).transpose();
    const Eigen::Vector3d q = lifted(r[i], lamr);
    M.row(2 * i) << Eigen::RowVector3d::Zero(), -q.z() * p, q.y() * p;
    M.row(2 * i + 1) << q.z() * p, Eigen::RowVector3d::Zero(), -q.x() * p;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(M, Eigen::ComputeFullV);
  const Eigen::Matrix<double, 9, 1> h = svd.matrixV().col(8);
  Eigen::Matrix3d H;
  H << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), h(8);
  return H;
}

// Gauge: the largest entry of each H is fixed to 1 and the other eight are free.
struct Gauge {
  int fixed = 8;
};

Gauge gauge_of(Eigen::Matrix3d& H) {
  Eigen::Index r = 0, c = 0;
  H.cwiseAbs().maxCoeff(&r, &c);
  H /= H(r, c);
  return {static_cast<int>(3 * r + c)};
}

Eigen::Matrix3d unpack(const double* p, Gauge g) {
  Eigen::Matrix3d H;
  for (int k = 0, j = 0; k < 9; ++k) H(k / 3, k % 3) = (k == g.fixed) ? 1.0 : p[j++];
  return H;
}

void pack(const Eigen::Matrix3d& H, Gauge g, double* p) {
  for (int k = 0, j = 0; k < 9; ++k) {
    if (k != g.fixed) p[j++] = H(k / 3, k % 3);
  }
}

// Joint problem in conditioned coordinates: params (lambda, lambda', 8 per plane). Each plane's residuals
// depend on the two lambdas and its own 8 entries only, so the normal equations are assembled from
// 10-column blocks (cv::LMSolver would form the dense J^T J of every plane, ~100x slower at 19 planes).
class JointProblem {
 public:
  JointProblem(std::span<const PlaneCorrespondences> planes, std::vector<Gauge> gauges)
      : planes_(planes), gauges_(std::move(gauges)) {
    offsets_.push_back(0);
    for (const auto& p : planes_) offsets_.push_back(offsets_.back() + 4 * static_cast<int>(p.left.size()));
  }
  int residual_count() const { return offsets_.back(); }
  int param_count() const { return 2 + 8 * static_cast<int>(planes_.size()); }

  void residuals(const double* x, int plane, double* out) const {
    const Eigen::Matrix3d H = unpack(x + 2 + 8 * plane, gauges_[plane]);
    const auto& p = planes_[plane];
    transfer(H, H.inverse(), x[0], x[1], p.left, p.right, out);
  }
  void all_residuals(const double* x, double* out) const {
    for (std::size_t b = 0; b < planes_.size(); ++b) residuals(x, static_cast<int>(b), out + offsets_[b]);
  }

  // J^T J and J^T r at x, from central differences (truncation error ~ h^2 ~ 1e-14).
  void normal_equations(Eigen::VectorXd& x, Eigen::MatrixXd& JtJ, Eigen::VectorXd& Jtr) const {
    const int n = param_count();
    JtJ.setZero(n, n);
    Jtr.setZero(n);
    for (int b = 0; b < static_cast<int>(planes_.size()); ++b) {
      const int m = offsets_[b + 1] - offsets_[b];
      Eigen::VectorXd r(m), plus(m), minus(m);
      Eigen::MatrixXd J(m, 10);
      residuals(x.data(), b, r.data());
      for (int k = 0; k < 10; ++k) {
        const int j = k < 2 ? k : 2 + 8 * b + (k - 2);
        const double keep = x(j), h = 1e-7 * std::max(1.0, std::abs(keep));
        x(j) = keep + h;
        residuals(x.data(), b, plus.data());
        x(j) = keep - h;
        residuals(x.data(), b, minus.data());
        x(j) = keep;
        J.col(k) = (plus - minus) / (2.0 * h);
      }
      const Eigen::MatrixXd JtJb = J.transpose() * J;
      const Eigen::VectorXd Jtrb = J.transpose() * r;
      const int o = 2 + 8 * b;
      JtJ.topLeftCorner<2, 2>() += JtJb.topLeftCorner<2, 2>();
      JtJ.block(0, o, 2, 8) += JtJb.topRightCorner<2, 8>();
      JtJ.block(o, 0, 8, 2) += JtJb.bottomLeftCorner<8, 2>();
      JtJ.block(o, o, 8, 8) += JtJb.bottomRightCorner<8, 8>();
      Jtr.head<2>() += Jtrb.head<2>();
      Jtr.segment<8>(o) += Jtrb.tail<8>();
    }
  }

  double cost(const Eigen::VectorXd& x, Eigen::VectorXd& r) const {
    r.resize(residual_count());
    all_residuals(x.data(), r.data());
    return r.squaredNorm();
  }

  // Levenberg-Marquardt with Marquardt's diagonal scaling; returns the iterations taken.
  int minimise(Eigen::VectorXd& x, int max_iterations) const {
    Eigen::VectorXd r, rn;
    double c = cost(x, r), mu = 1e-3;
    Eigen::MatrixXd JtJ;
    Eigen::VectorXd Jtr;
    int it = 0;
    for (; it < max_iterations && c > 0.0; ++it) {
      normal_equations(x, JtJ, Jtr);
      const Eigen::VectorXd D = JtJ.diagonal().cwiseMax(1e-12);
      bool accepted = false;
      Eigen::VectorXd dx;
      while (mu < 1e12) {
        Eigen::MatrixXd A = JtJ;
        A.diagonal() += mu * D;
        dx = -A.ldlt().solve(Jtr);
        const Eigen::VectorXd xn = x + dx;
        const double cn = cost(xn, rn);
        if (std::isfinite(cn) && cn < c) {
          const bool tiny = c - cn <= 1e-15 * c;
          x = xn;
          c = cn;
          mu = std::max(mu / 3.0, 1e-12);
          accepted = !tiny;
          break;
        }
        mu *= 4.0;
      }
      if (!accepted || dx.lpNorm<Eigen::Infinity>() <= 1e-14 * std::max(1.0, x.lpNorm<Eigen::Infinity>())) {
        ++it;
        break;
      }
    }
    return it;
  }

 private:
  std::span<const PlaneCorrespondences> planes_;
  std::vector<Gauge> gauges_;
  std::vector<int> offsets_;
};

Eigen::Matrix3d normalised(const Eigen::Matrix3d& H) {
  Eigen::Index r = 0, c = 0;
  H.cwiseAbs().maxCoeff(&r, &c);
  return (H(r, c) < 0 ? -1.0 : 1.0) * H / H.norm();
}

struct Solved {
  bool ok = false;
  double lam = 0, lamr = 0, linear_rms = 0, rms = 0;
  std::vector<Eigen::Matrix3d> H;
  int iterations = 0;
};

Solved solve(std::span<const PlaneCorrespondences> planes, const DivisionHomographySettings& opt) {
  Solved out;
  if (planes.empty()) return out;
  // Condition: scale every coordinate by the RMS radius so that radii are ~1 (lambda~ = lambda s^2).
  double sum = 0;
  std::size_t count = 0;
  for (const auto& p : planes) {
    if (p.left.size() != p.right.size() || p.left.size() < 8) return out;
    for (std::size_t i = 0; i < p.left.size(); ++i) sum += p.left[i].squaredNorm() + p.right[i].squaredNorm();
    count += 2 * p.left.size();
  }
  const double s = sum > 0 ? std::sqrt(sum / static_cast<double>(count)) : 1.0;
  std::vector<PlaneCorrespondences> sc(planes.size());
  for (std::size_t b = 0; b < planes.size(); ++b) {
    for (const auto& v : planes[b].left) sc[b].left.push_back(v / s);
    for (const auto& v : planes[b].right) sc[b].right.push_back(v / s);
  }

  std::vector<Eigen::Matrix3d> Hs(planes.size());
  std::vector<double> lams, lamrs;
  for (std::size_t b = 0; b < sc.size(); ++b) {
    double lam = 0, lamr = 0;
    if (linear_solve(sc[b].left, sc[b].right, Hs[b], lam, lamr)) {
      lams.push_back(lam);
      lamrs.push_back(lamr);
    }
  }
  if (lams.empty()) return out;
  // Copies: the medians reorder.
  double lam = base::upper_median(std::vector<double>(lams)),
         lamr = base::upper_median(std::vector<double>(lamrs));
  // One plane keeps its own linear H; several planes restart every H from the shared lambdas.
  if (sc.size() > 1 || lams.size() != 1) {
    for (std::size_t b = 0; b < sc.size(); ++b) Hs[b] = dlt_fixed_lambda(sc[b].left, sc[b].right, lam, lamr);
  }

  std::vector<Gauge> gauges;
  for (auto& H : Hs) gauges.push_back(gauge_of(H));
  const JointProblem problem(std::span<const PlaneCorrespondences>(sc), gauges);
  Eigen::VectorXd x(problem.param_count());
  x(0) = lam;
  x(1) = lamr;
  for (std::size_t b = 0; b < sc.size(); ++b) pack(Hs[b], gauges[b], x.data() + 2 + 8 * b);
  Eigen::VectorXd res;
  const double n_res = std::max(1, problem.residual_count());
  out.linear_rms = std::sqrt(problem.cost(x, res) / n_res) * s;
  if (opt.refine) out.iterations = problem.minimise(x, opt.max_iterations);
  out.rms = std::sqrt(problem.cost(x, res) / n_res) * s;

  // Back to model coordinates: x~ = S^-1 x with S = diag(s, s, 1), so H = S H~ S^-1, lambda = lambda~ / s^2.
  const Eigen::Matrix3d S = Eigen::Vector3d(s, s, 1.0).asDiagonal();
  const Eigen::Matrix3d Si = Eigen::Vector3d(1.0 / s, 1.0 / s, 1.0).asDiagonal();
  out.lam = x(0) / (s * s);
  out.lamr = x(1) / (s * s);
  for (std::size_t b = 0; b < sc.size(); ++b) {
    out.H.push_back(normalised(S * unpack(x.data() + 2 + 8 * b, gauges[b]) * Si));
  }
  out.ok = std::isfinite(out.lam) && std::isfinite(out.lamr) && std::isfinite(out.rms);
  return out;
}

}  // namespace

DivisionHomography estimate_division_homography(std::span<const Eigen::Vector2d> left,
                                                std::span<const Eigen::Vector2d> right,
                                                const DivisionHomographySettings& opt) {
  PlaneCorrespondences plane;
  plane.left.assign(left.begin(), left.end());
  plane.right.assign(right.begin(), right.end());
  const Solved s = solve(std::span<const PlaneCorrespondences>(&plane, 1), opt);
  DivisionHomography out;
  out.ok = s.ok;
  if (!s.ok) return out;
  out.H = s.H.front();
  out.lambda_left = s.lam;
  out.lambda_right = s.lamr;
  out.linear_rms = s.linear_rms;
  out.rms = s.rms;
  out.iterations = s.iterations;
  return out;
}

DivisionLambdas estimate_division_lambdas(std::span<const PlaneCorrespondences> planes,
                                          const DivisionHomographySettings& opt) {
  const Solved s = solve(planes, opt);
  DivisionLambdas out;
  out.ok = s.ok;
  if (!s.ok) return out;
  out.lambda_left = s.lam;
  out.lambda_right = s.lamr;
  out.H = s.H;
  out.rms = s.rms;
  out.iterations = s.iterations;
  return out;
}

}  // namespace naneye::recon
