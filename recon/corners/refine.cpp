#include "naneye/recon/corners/refine.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <array>
#include <cmath>

namespace naneye::recon {
namespace {

constexpr int kParams = 11;  // qx qy t1 t2 s a gx gy b hx hy
constexpr int kMaxHalf = 9;  // radius <= 8: the work space lives on the stack (~90 KB)
constexpr int kMaxPixels = (2 * kMaxHalf + 1) * (2 * kMaxHalf + 1);
using Vec = Eigen::Matrix<double, kParams, 1>;
using Mat = Eigen::Matrix<double, kParams, kParams>;

struct Window {
  int n = 0;
  double inv_half = 1;
  std::array<double, kMaxPixels> dx{}, dy{}, yx{}, yy{}, val{};
  std::array<double, kMaxPixels> wt{};
  // Work space of the normal equations: Jacobian rows, weighted residuals, sqrt of the weights.
  Eigen::Matrix<double, kMaxPixels, kParams, Eigen::RowMajor> rows;
  Eigen::Matrix<double, kMaxPixels, 1> wr, sw;
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

// erf(x) and exp(-x^2) together: Abramowitz & Stegun 7.1.26 (|error| <= 1.5e-7, far below the
// noise of a 10-bit pixel), which needs exp(-x^2) anyway, and so does the derivative of erf.
inline double erf_and_gauss(double x, double& gauss) {
  constexpr double p = 0.3275911, a1 = 0.254829592, a2 = -0.284496736, a3 = 1.421413741, a4 = -1.453152027,
                   a5 = 1.061405429;
  const double ax = std::abs(x);
  gauss = std::exp(-x * x);
  const double t = 1.0 / (1.0 + p * ax);
  const double y = 1.0 - (((((a5 * t + a4) * t) + a3) * t + a2) * t + a1) * t * gauss;
  return x < 0 ? -y : y;
}

struct Eval {
  double cost = 0;
  double used = 0;  // sum of weights
};

// Residuals and (optionally) the normal equations of the model at parameters p.
Eval evaluate(Window& w, const Vec& p, Mat* JtJ, Vec* Jtr, std::array<double, kMaxPixels>* res) {
  auto* rows = &w.rows;
  auto& wr = w.wr;
  auto& sw = w.sw;
  constexpr double kInvSqrt2 = 0.70710678118654752440;
  constexpr double kTwoOverSqrtPi = 1.12837916709551257390;
  const double c1 = std::cos(p[2]), s1 = std::sin(p[2]), c2 = std::cos(p[3]), s2 = std::sin(p[3]);
  const double sig = p[4], inv_s = 1.0 / sig, k = kInvSqrt2 * inv_s;
  Eval e;
  for (int i = 0; i < w.n; ++i) {
    const double rx = w.yx[i] - p[0], ry = w.yy[i] - p[1];
    const double u1 = c1 * rx + s1 * ry, u2 = c2 * rx + s2 * ry;
    double g1, g2;
    const double E1 = erf_and_gauss(k * u1, g1), E2 = erf_and_gauss(k * u2, g2);
    const double dx = w.dx[i] * w.inv_half, dy = w.dy[i] * w.inv_half;
    const double C = p[8] + p[9] * dx + p[10] * dy;
    const double S = E1 * E2;
    const double r = p[5] + p[6] * dx + p[7] * dy + C * S - w.val[i];
    if (res) (*res)[i] = r;
    const double wt = w.wt[i];
    e.cost += wt * r * r;
    e.used += wt;
    if (!JtJ) continue;
    if (wt <= 0.0) {
      rows->row(i).setZero();
      wr[i] = 0;
      sw[i] = 0;
      continue;
    }
    const double G1 = kTwoOverSqrtPi * k * g1, G2 = kTwoOverSqrtPi * k * g2;
    const double A = C * G1 * E2, B = C * E1 * G2;
    auto J = rows->row(i);
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
    wr[i] = wt * r;
    sw[i] = std::sqrt(wt);
  }
  if (JtJ) {
    // One matrix product for the normal equations (vectorised) instead of a rank-1 update per pixel.
    const auto Jn = rows->topRows(w.n);
    *Jtr = Jn.transpose() * wr.head(w.n);
    const Eigen::Matrix<double, Eigen::Dynamic, kParams, 0, kMaxPixels, kParams> Jw =
        sw.head(w.n).asDiagonal() * Jn;
    JtJ->noalias() = Jw.transpose() * Jw;
  }
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
    double g;
    const double S = erf_and_gauss(k * (c1 * rx + s1 * ry), g) * erf_and_gauss(k * (c2 * rx + s2 * ry), g);
    const double dx = w.dx[i] * w.inv_half, dy = w.dy[i] * w.inv_half;
    Eigen::Matrix<double, 6, 1> J;
    J << 1.0, dx, dy, S, dx * S, dy * S;
    A.selfadjointView<Eigen::Upper>().rankUpdate(J, w.wt[i]);
    rhs += J * (w.wt[i] * w.val[i]);
  }
  A = A.selfadjointView<Eigen::Upper>();
  A.diagonal().array() += 1e-9 * (A.diagonal().maxCoeff() + 1.0);
  const Eigen::Matrix<double, 6, 1> sol = A.ldlt().solve(rhs);
  p.segment<6>(5) = sol;
}

int levenberg_marquardt(Window& w, Vec& p, int max_iterations, double tolerance_px) {
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
      const bool small = step.head<2>().norm() < tolerance_px;
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

bool fit_saddle(const LumaView& img, const CameraModel& cam, const SaddleInit& init, double radius,
                int max_iterations, SaddleFit& out, double tolerance_px) {
  out = SaddleFit{};
  // Pixels up to `radius` (Chebyshev distance from the initial corner) weigh 1, with a 1 px linear
  // taper beyond: the fit then varies continuously with where it starts and with the radius, so
  // that tracking and full search agree (a hard window jumps when its centre rounds differently).
  const int half = static_cast<int>(std::ceil(radius)) + 1;
  if (radius < 1.5 || half > kMaxHalf) return false;
  const int cx = static_cast<int>(std::lround(init.px.x())), cy = static_cast<int>(std::lround(init.px.y()));
  if (cx - half < 0 || cx + half >= img.col_end || cy - half < img.row_begin || cy + half >= img.row_end) {
    return false;
  }
  const Eigen::Vector2d c(cx, cy);
  const Eigen::Vector2d off = init.px - c;
  Eigen::Vector2d x0 = Eigen::Vector2d::Zero();
  Eigen::Matrix2d Jp = Eigen::Matrix2d::Identity(), L = Eigen::Matrix2d::Identity();
  Eigen::Matrix2d H[2] = {Eigen::Matrix2d::Zero(), Eigen::Matrix2d::Zero()};
  const bool undist = local_map(cam, c, half, x0, Jp, L, H);

  Window w;
  w.inv_half = 1.0 / half;
  for (int r = -half; r <= half; ++r) {
    for (int q = -half; q <= half; ++q) {
      const double cheb = std::max(std::abs(q - off.x()), std::abs(r - off.y()));
      const double wt = std::clamp(radius + 0.5 - cheb, 0.0, 1.0);
      if (wt <= 0.0) continue;
      const int i = w.n++;
      const Eigen::Vector2d d(q, r);
      Eigen::Vector2d y = d;
      if (undist) y = L * d + 0.5 * Eigen::Vector2d(d.dot(H[0] * d), d.dot(H[1] * d));
      w.dx[i] = q;
      w.dy[i] = r;
      w.yx[i] = y.x();
      w.yy[i] = y.y();
      w.val[i] = img.at(cy + r, cx + q);
      w.wt[i] = wt;
    }
  }

  Vec p;
  const Eigen::Vector2d d0 = init.px - c;
  const Eigen::Vector2d q0 = undist ? Eigen::Vector2d(L * d0) : d0;
  p << q0.x(), q0.y(), init.theta1, init.theta2, init.sigma, 0, 0, 0, 0, 0, 0;
  init_linear(w, p);
  out.iterations = levenberg_marquardt(w, p, max_iterations, tolerance_px);

  std::array<double, kMaxPixels> res{};
  const Eval e = evaluate(w, p, nullptr, nullptr, &res);
  const double rms = std::sqrt(e.cost / std::max(1.0, e.used));
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
