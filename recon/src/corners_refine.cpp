#include "naneye/recon/corners_refine.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <array>
#include <cmath>

namespace naneye::recon {
namespace {

constexpr int kParams = 11;  // qx qy t1 t2 s a gx gy b hx hy
constexpr int kMaxHalf = 9;
constexpr int kMaxPixels = (2 * kMaxHalf + 1) * (2 * kMaxHalf + 1);
using Vec = Eigen::Matrix<double, kParams, 1>;
using Mat = Eigen::Matrix<double, kParams, kParams>;

struct Window {
  int n = 0;
  double inv_half = 1;
  std::array<double, kMaxPixels> dx{}, dy{}, yx{}, yy{}, val{};
  std::array<bool, kMaxPixels> use{};
};

// The window's local undistorted coordinates (see the header). A quadratic interpolation of the
// exact undistortion through 9 exact samples (centre, edge midpoints, corners of the window): the
// cubic remainder over a +-7 px window is below 0.01 px for this lens, and it saves ~170 Newton
// solves per corner. Returns false when any sample lies beyond the fold.
bool local_map(const CameraModel& cam, const Eigen::Vector2d& c, int half, Eigen::Vector2d& x0,
               Eigen::Matrix2d& Jp, Eigen::Matrix2d& L, Eigen::Matrix2d H[2]) {
  const Undistorted u0 = cam.undistort(c);
  if (!u0.ok()) return false;
  x0 = u0.normalized;
  Eigen::Matrix2d Kaff;
  Kaff << cam.fx(), cam.skew(), 0.0, cam.fy();
  Jp = Kaff * cam.distort_jacobian(x0);
  const double h = half;
  Eigen::Vector2d g[3][3];
  for (int i = -1; i <= 1; ++i) {
    for (int j = -1; j <= 1; ++j) {
      if (i == 0 && j == 0) {
        g[1][1].setZero();
        continue;
      }
      const Undistorted u = cam.undistort(c + Eigen::Vector2d(i * h, j * h));
      if (!u.ok()) return false;
      g[i + 1][j + 1] = Jp * (u.normalized - x0);
    }
  }
  const Eigen::Vector2d gx = (g[2][1] - g[0][1]) / (2 * h), gy = (g[1][2] - g[1][0]) / (2 * h);
  L.col(0) = gx;
  L.col(1) = gy;
  const Eigen::Vector2d gxx = (g[2][1] + g[0][1]) / (h * h), gyy = (g[1][2] + g[1][0]) / (h * h);
  const Eigen::Vector2d gxy = (g[2][2] - g[2][0] - g[0][2] + g[0][0]) / (4 * h * h);
  for (int k = 0; k < 2; ++k) H[k] << gxx[k], gxy[k], gxy[k], gyy[k];
  return true;
}

struct Eval {
  double cost = 0;
  int used = 0;
};

// Residuals and (optionally) the normal equations of the model at parameters p.
Eval evaluate(const Window& w, const Vec& p, Mat* JtJ, Vec* Jtr, std::array<double, kMaxPixels>* res) {
  constexpr double kInvSqrt2 = 0.70710678118654752440;
  constexpr double kTwoOverSqrtPi = 1.12837916709551257390;
  const double c1 = std::cos(p[2]), s1 = std::sin(p[2]), c2 = std::cos(p[3]), s2 = std::sin(p[3]);
  const double sig = p[4], inv_s = 1.0 / sig, k = kInvSqrt2 * inv_s;
  Eval e;
  if (JtJ) {
    JtJ->setZero();
    Jtr->setZero();
  }
  for (int i = 0; i < w.n; ++i) {
    const double rx = w.yx[i] - p[0], ry = w.yy[i] - p[1];
    const double u1 = c1 * rx + s1 * ry, u2 = c2 * rx + s2 * ry;
    const double E1 = std::erf(k * u1), E2 = std::erf(k * u2);
    const double dx = w.dx[i] * w.inv_half, dy = w.dy[i] * w.inv_half;
    const double C = p[8] + p[9] * dx + p[10] * dy;
    const double S = E1 * E2;
    const double r = p[5] + p[6] * dx + p[7] * dy + C * S - w.val[i];
    if (res) (*res)[i] = r;
    if (!w.use[i]) continue;
    e.cost += r * r;
    ++e.used;
    if (!JtJ) continue;
    const double G1 = kTwoOverSqrtPi * k * std::exp(-(k * u1) * (k * u1));
    const double G2 = kTwoOverSqrtPi * k * std::exp(-(k * u2) * (k * u2));
    const double A = C * G1 * E2, B = C * E1 * G2;
    Vec J;
    J[0] = -(A * c1 + B * c2);
    J[1] = -(A * s1 + B * s2);
    J[2] = A * (-s1 * rx + c1 * ry);
    J[3] = B * (-s2 * rx + c2 * ry);
    J[4] = -(A * u1 + B * u2) * inv_s;
    J[5] = 1.0;
    J[6] = dx;
    J[7] = dy;
    J[8] = S;
    J[9] = dx * S;
    J[10] = dy * S;
    JtJ->selfadjointView<Eigen::Upper>().rankUpdate(J);
    *Jtr += J * r;
  }
  if (JtJ) *JtJ = JtJ->selfadjointView<Eigen::Upper>();
  return e;
}

// The shading parameters are linear for fixed geometry: initialise them by linear least squares.
void init_linear(const Window& w, Vec& p) {
  constexpr double kInvSqrt2 = 0.70710678118654752440;
  const double c1 = std::cos(p[2]), s1 = std::sin(p[2]), c2 = std::cos(p[3]), s2 = std::sin(p[3]);
  const double k = kInvSqrt2 / p[4];
  Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> rhs = Eigen::Matrix<double, 6, 1>::Zero();
  for (int i = 0; i < w.n; ++i) {
    const double rx = w.yx[i] - p[0], ry = w.yy[i] - p[1];
    const double S = std::erf(k * (c1 * rx + s1 * ry)) * std::erf(k * (c2 * rx + s2 * ry));
    const double dx = w.dx[i] * w.inv_half, dy = w.dy[i] * w.inv_half;
    Eigen::Matrix<double, 6, 1> J;
    J << 1.0, dx, dy, S, dx * S, dy * S;
    A.selfadjointView<Eigen::Upper>().rankUpdate(J);
    rhs += J * w.val[i];
  }
  A = A.selfadjointView<Eigen::Upper>();
  A.diagonal().array() += 1e-9 * (A.diagonal().maxCoeff() + 1.0);
  const Eigen::Matrix<double, 6, 1> sol = A.ldlt().solve(rhs);
  p.segment<6>(5) = sol;
}

int levenberg_marquardt(const Window& w, Vec& p, int max_iterations) {
  Mat JtJ;
  Vec Jtr;
  double cost = evaluate(w, p, &JtJ, &Jtr, nullptr).cost;
  double lambda = 1e-3;
  int it = 0;
  for (; it < max_iterations; ++it) {
    Mat A = JtJ;
    A.diagonal() += lambda * JtJ.diagonal().cwiseMax(1e-12);
    const Vec step = -A.ldlt().solve(Jtr);
    if (!step.allFinite()) break;
    Vec cand = p + step;
    if (!(cand[4] > 0.05)) cand[4] = 0.05;
    Mat JtJ2;
    Vec Jtr2;
    const double c2 = evaluate(w, cand, &JtJ2, &Jtr2, nullptr).cost;
    if (c2 < cost) {
      p = cand;
      JtJ = JtJ2;
      Jtr = Jtr2;
      const bool small = step.head<2>().norm() < 1e-5 && cost - c2 < 1e-10 * cost;
      cost = c2;
      lambda = std::max(lambda * 0.2, 1e-9);
      if (small) break;
    } else {
      lambda *= 10.0;
      if (lambda > 1e8) break;
    }
  }
  return it + 1;
}

}  // namespace

bool fit_saddle(const LumaView& img, const CameraModel& cam, const SaddleInit& init, int half,
                int max_iterations, SaddleFit& out) {
  out = SaddleFit{};
  if (half < 2 || half > kMaxHalf) return false;
  const int cx = static_cast<int>(std::lround(init.px.x())), cy = static_cast<int>(std::lround(init.px.y()));
  if (cx - half < 0 || cx + half >= img.col_end || cy - half < img.row_begin || cy + half >= img.row_end) {
    return false;
  }
  const Eigen::Vector2d c(cx, cy);
  Eigen::Vector2d x0 = Eigen::Vector2d::Zero();
  Eigen::Matrix2d Jp = Eigen::Matrix2d::Identity(), L = Eigen::Matrix2d::Identity();
  Eigen::Matrix2d H[2] = {Eigen::Matrix2d::Zero(), Eigen::Matrix2d::Zero()};
  const bool undist = local_map(cam, c, half, x0, Jp, L, H);

  Window w;
  w.inv_half = 1.0 / half;
  for (int r = -half; r <= half; ++r) {
    for (int q = -half; q <= half; ++q) {
      const int i = w.n++;
      const Eigen::Vector2d d(q, r);
      Eigen::Vector2d y = d;
      if (undist) y = L * d + 0.5 * Eigen::Vector2d(d.dot(H[0] * d), d.dot(H[1] * d));
      w.dx[i] = q;
      w.dy[i] = r;
      w.yx[i] = y.x();
      w.yy[i] = y.y();
      w.val[i] = img.at(cy + r, cx + q);
      w.use[i] = true;
    }
  }

  Vec p;
  const Eigen::Vector2d d0 = init.px - c;
  const Eigen::Vector2d q0 = undist ? Eigen::Vector2d(L * d0) : d0;
  p << q0.x(), q0.y(), init.theta1, init.theta2, init.sigma, 0, 0, 0, 0, 0, 0;
  init_linear(w, p);
  out.iterations = levenberg_marquardt(w, p, max_iterations);

  // Defect pixels (hot or dead, datasheet: < 10 per sensor) bias a least-squares fit: drop pixels
  // whose residual is far beyond the rest and refit once.
  std::array<double, kMaxPixels> res{};
  Eval e = evaluate(w, p, nullptr, nullptr, &res);
  double rms = std::sqrt(e.cost / std::max(1, e.used));
  int dropped = 0;
  for (int i = 0; i < w.n; ++i) {
    if (std::abs(res[i]) > std::max(5.0 * rms, 1e-6)) {
      w.use[i] = false;
      ++dropped;
    }
  }
  if (dropped > 0 && dropped <= 4) {
    out.iterations += levenberg_marquardt(w, p, max_iterations);
    e = evaluate(w, p, nullptr, nullptr, &res);
    rms = std::sqrt(e.cost / std::max(1, e.used));
  }
  out.outliers = dropped;
  out.theta1 = p[2];
  out.theta2 = p[3];
  out.sigma = p[4];
  out.contrast = std::abs(p[8]);
  out.rms = rms;
  out.undistorted = undist;
  const Eigen::Vector2d q(p[0], p[1]);
  if (!p.allFinite() || q.cwiseAbs().maxCoeff() > half) return false;
  if (std::abs(std::sin(p[2] - p[3])) < 0.3) return false;  // edges (nearly) parallel: not a corner
  if (undist) {
    const Eigen::Vector2d xn = x0 + Jp.inverse() * q;
    out.px = cam.to_pixel(cam.distort(xn));
  } else {
    out.px = c + q;
  }
  out.converged = true;
  return true;
}

}  // namespace naneye::recon
