#include "naneye/recon/corners/sine_fit.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace naneye::recon {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kParams = 13;  // qx qy m00 m01 m10 m11 a gx gy b hx hy c
using Vec = Eigen::Matrix<double, kParams, 1>;
using Mat = Eigen::Matrix<double, kParams, kParams>;
// The start is a lattice point of the coarse grid or of the first pass (within ~1 px at 4 px
// squares): a fit that ends more than this share of a step away found the next lattice point, where
// the model repeats (with b's sign flipped), not this corner.
constexpr double kMaxMoveSteps = 0.35;

// The weighted Jacobian of one window, one column per parameter (fixed capacity: no heap).
using Jac =
    Eigen::Matrix<float, Eigen::Dynamic, kParams, Eigen::ColMajor, FastFitScratch::kMaxPixels, kParams>;

// The weighted cost at p and, when JtJ is non-null, the normal equations (Gauss-Newton) of all 13
// parameters (the seven linear terms are rows 6-12). In float over the window's arrays, as
// fit_saddle_fast is (Eigen vectorises the sines and cosines): the corner's precision needs ~1e-3
// px of a few-px window, far inside float's 1e-7.
double evaluate(FastFitScratch& w, int n, const Vec& p, Jac& J, Mat* JtJ, Vec* Jtr) {
  constexpr float kPiF = static_cast<float>(kPi);
  const auto pf = p.cast<float>();
  const auto ex = w.yx.head(n) - pf[0], ey = w.yy.head(n) - pf[1];
  auto u = w.U1.head(n), v = w.U2.head(n);  // pi u, pi v
  u = kPiF * (pf[2] * ex + pf[3] * ey);
  v = kPiF * (pf[4] * ex + pf[5] * ey);
  auto su = w.E1.head(n), cu = w.E2.head(n), sv = w.G1.head(n), cv = w.G2.head(n);
  su = u.sin();
  cu = u.cos();
  sv = v.sin();
  cv = v.cos();
  const auto dx = w.dx.head(n), dy = w.dy.head(n);
  auto S = w.S.head(n), r = w.r.head(n);
  S = su * sv;
  auto C = w.Jw[4].head(n);
  C = cu * cv;
  r = pf[6] + pf[7] * dx + pf[8] * dy + (pf[9] + pf[10] * dx + pf[11] * dy) * S + pf[12] * C - w.val.head(n);
  const double cost = static_cast<double>((w.wt.head(n) * r.square()).sum());
  if (!JtJ) return cost;
  // Columns scaled by sqrt(wt), so that J' J is the weighted normal matrix.
  auto sw = w.Jw[0].head(n), swB = w.Jw[1].head(n), Su = w.Jw[2].head(n), Sv = w.Jw[3].head(n);
  sw = w.wt.head(n).sqrt();
  swB = sw * (pf[9] + pf[10] * dx + pf[11] * dy) * kPiF;
  Su = swB * cu * sv - (kPiF * pf[12]) * sw * su * cv;  // sqrt(wt) d model / du
  Sv = swB * su * cv - (kPiF * pf[12]) * sw * cu * sv;
  J.resize(n, kParams);
  J.col(0) = -(Su * pf[2] + Sv * pf[4]).matrix();
  J.col(1) = -(Su * pf[3] + Sv * pf[5]).matrix();
  J.col(2) = (Su * ex).matrix();
  J.col(3) = (Su * ey).matrix();
  J.col(4) = (Sv * ex).matrix();
  J.col(5) = (Sv * ey).matrix();
  J.col(6) = sw.matrix();
  J.col(7) = (sw * dx).matrix();
  J.col(8) = (sw * dy).matrix();
  J.col(9) = (sw * S).matrix();
  J.col(10) = (sw * dx * S).matrix();
  J.col(11) = (sw * dy * S).matrix();
  J.col(12) = (sw * C).matrix();
  *JtJ = J.transpose().lazyProduct(J).cast<double>();  // coefficient-wise: no GEMM packing for 13 x 13
  *Jtr = (J.transpose() * (sw * r).matrix()).cast<double>();
  return cost;
}

}  // namespace

bool fit_sine_corner(const LumaView& img, const CameraModel& cam, const UndistortMap& map,
                     const SineInit& init, int max_iterations, double tolerance_px, FastFitScratch& w,
                     SaddleFit& out) {
  out = SaddleFit{};
  out.harmonic = true;
  // The steps in local coordinates: y ~ p - c to first order, and M is fitted anyway.
  Eigen::Matrix2d steps;
  steps << init.step_col, init.step_row;
  if (std::abs(steps.determinant()) < 1.0) return false;  // a cell under 1 px^2: no grid
  const Eigen::Matrix2d M0 = steps.inverse();
  const double min_step = std::min(init.step_col.norm(), init.step_row.norm());
  double u_lo = init.border_col_lo ? init.border_extent : init.extent_col;
  double u_hi = init.border_col_hi ? init.border_extent : init.extent_col;
  double v_lo = init.border_row_lo ? init.border_extent : init.extent_row;
  double v_hi = init.border_row_hi ? init.border_extent : init.extent_row;
  // The pixel window that holds the grid window: its parallelogram's farthest corner; a grid
  // window beyond the work space is shrunk to fit it (squares of 6-8 px seen at an angle).
  const Eigen::Vector2d reach =
      (init.step_col * std::max(u_lo, u_hi)).cwiseAbs() + (init.step_row * std::max(v_lo, v_hi)).cwiseAbs();
  constexpr double kMaxRadius = FastFitScratch::kMaxHalf - 1;
  if (reach.maxCoeff() > kMaxRadius) {
    const double shrink = kMaxRadius / reach.maxCoeff();
    u_lo *= shrink;
    u_hi *= shrink;
    v_lo *= shrink;
    v_hi *= shrink;
  }
  const double radius = std::clamp(reach.maxCoeff(), 1.5, kMaxRadius);
  FitWindow win;
  if (!load_fit_window(img, cam, map, init.px, radius, w, win)) return false;
  const int n = win.n;
  {
    // The grid window's taper, 1 px wide along each axis, from the start's geometry (fixed during
    // the fit, so that its cost stays one function).
    const double len_col = init.step_col.norm(), len_row = init.step_row.norm();
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2d uv = M0 * (Eigen::Vector2d(w.yx[i], w.yy[i]) - win.off);
      const double eu = uv.x() < 0 ? u_lo : u_hi, ev = uv.y() < 0 ? v_lo : v_hi;
      const double tu = std::clamp((eu - std::abs(uv.x())) * len_col + 0.5, 0.0, 1.0);
      const double tv = std::clamp((ev - std::abs(uv.y())) * len_row + 0.5, 0.0, 1.0);
      w.wt[i] = static_cast<float>(w.wt[i] * tu * tv);
    }
  }

  Jac rows;
  Vec p = Vec::Zero();
  p << win.off.x(), win.off.y(), M0(0, 0), M0(0, 1), M0(1, 0), M0(1, 1), 0, 0, 0, 0, 0, 0, 0;
  // The seven linear terms for the start's geometry: one linear least-squares solve.
  {
    Mat JtJ;
    Vec Jtr;
    evaluate(w, n, p, rows, &JtJ, &Jtr);
    Eigen::Matrix<double, 7, 7> A = JtJ.block<7, 7>(6, 6);
    A.diagonal().array() += 1e-9 * (A.diagonal().maxCoeff() + 1.0);
    p.segment<7>(6) -= A.ldlt().solve(Jtr.segment<7>(6));
  }
  Mat JtJ, JtJ2;
  Vec Jtr, Jtr2;
  double cost = evaluate(w, n, p, rows, &JtJ, &Jtr);
  double lambda = 1e-3;
  int it = 0;
  for (; it < max_iterations; ++it) {
    Mat A = JtJ;
    A.diagonal() += lambda * JtJ.diagonal().cwiseMax(1e-12);
    const Vec step = -A.ldlt().solve(Jtr);
    if (!step.allFinite()) break;
    const Vec cand = p + step;
    const double c2 = evaluate(w, n, cand, rows, &JtJ2, &Jtr2);
    if (c2 < cost) {
      p = cand;
      JtJ = JtJ2;
      Jtr = Jtr2;
      cost = c2;
      lambda = std::max(lambda * 0.2, 1e-9);
      if (step.head<2>().norm() < tolerance_px) break;
    } else {
      lambda *= 10.0;
      if (lambda > 1e8) break;
    }
  }
  out.iterations = it + 1;
  const double used = static_cast<double>(w.wt.head(n).sum());
  const Mat inv = JtJ.ldlt().solve(Mat::Identity());
  const Eigen::Matrix2d cq = inv.topLeftCorner<2, 2>();
  const double mid = 0.5 * (cq(0, 0) + cq(1, 1)), det = cq.determinant();
  const double position_var = mid + std::sqrt(std::max(mid * mid - det, 0.0));
  out.contrast = std::abs(p[9]);
  out.rms = std::sqrt(cost / std::max(1.0, used));
  out.weight = used;
  out.position_var_per_noise = std::isfinite(position_var) ? position_var : 1e30;
  out.undistorted = win.undistorted;
  const Eigen::Vector2d q(p[0], p[1]);
  if (!p.allFinite() || (q - win.off).norm() > kMaxMoveSteps * min_step) return false;
  Eigen::Matrix2d M;
  M << p[2], p[3], p[4], p[5];
  // The fitted steps must stay a grid cell of the start's (the lattice, not one of its harmonics).
  const Eigen::Matrix2d fitted_steps = M.inverse();
  if (!fitted_steps.allFinite() || (fitted_steps - steps).norm() > 0.5 * min_step) return false;
  out.theta1 = std::atan2(fitted_steps(1, 0), fitted_steps(0, 0)) + 0.5 * kPi;
  out.theta2 = std::atan2(fitted_steps(1, 1), fitted_steps(0, 1)) + 0.5 * kPi;
  place_corner(win, cam, q, p.data() + 6, out);
  out.converged = true;
  return true;
}

}  // namespace naneye::recon
