#include "naneye/recon/corners_fast_fit.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

namespace naneye::recon {
namespace {

constexpr int kParams = 11;  // qx qy t1 t2 s a gx gy b hx hy
constexpr double kTrustStepPx = 0.05;
using Arr = FastFitScratch::Arr;
using Vec = Eigen::Matrix<double, kParams, 1>;
// The normal equations of K active parameters: fixed sizes, so Eigen unrolls their solve.
template <int K>
using MatK = Eigen::Matrix<double, K, K>;
template <int K>
using VecK = Eigen::Matrix<double, K, 1>;

// Which parameters are fitted: all, or all but the two edge normals.
constexpr std::array<int, 11> kFull = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
constexpr std::array<int, 11> kFixedEdges = {0, 1, 4, 5, 6, 7, 8, 9, 10, -1, -1};

// erf(z) and exp(-z^2) of a whole array: Abramowitz & Stegun 7.1.26 (|error| <= 1.5e-7, below float
// precision), which needs exp(-z^2) anyway, and so does the derivative of erf. Eigen packets: the
// loop runs 4 (SSE) or 8 (AVX) pixels at a time whatever the compiler's optimisation level.
// `z` holds the arguments on entry and 1 / (1 + p |z|) on return (work space).
void erf_and_gauss(Arr& z, int n, Arr& e, Arr& g) {
  constexpr float p = 0.3275911f, a1 = 0.254829592f, a2 = -0.284496736f, a3 = 1.421413741f,
                  a4 = -1.453152027f, a5 = 1.061405429f;
  auto zn = z.head(n);
  g.head(n) = (-zn.square()).exp();
  // sign(z) without a select (Eigen 3.4 does not vectorise Select): +-1 but for |z| < 1e-30, where
  // erf(z) ~ 0 anyway.
  e.head(n) = (zn * 1e30f).max(-1.0f).min(1.0f);
  zn = (1.0f + p * zn.abs()).inverse();
  const auto t = z.head(n);
  e.head(n) *= 1.0f - ((((a5 * t + a4) * t + a3) * t + a2) * t + a1) * t * g.head(n);
}

struct Model {
  float qx, qy, c1, s1, c2, s2, k, inv_s, a, gx, gy, b, hx, hy;
  explicit Model(const Vec& p)
      : qx(float(p[0])),
        qy(float(p[1])),
        c1(float(std::cos(p[2]))),
        s1(float(std::sin(p[2]))),
        c2(float(std::cos(p[3]))),
        s2(float(std::sin(p[3]))),
        k(float(0.70710678118654752440 / p[4])),
        inv_s(float(1.0 / p[4])),
        a(float(p[5])),
        gx(float(p[6])),
        gy(float(p[7])),
        b(float(p[8])),
        hx(float(p[9])),
        hy(float(p[10])) {}
};

// The geometry part of the model at p: u1, u2, both erf and Gaussians, S = E1 E2.
void shape(FastFitScratch& w, int n, const Model& m) {
  const auto yx = w.yx.head(n), yy = w.yy.head(n);
  w.U1.head(n) = m.c1 * (yx - m.qx) + m.s1 * (yy - m.qy);
  w.U2.head(n) = m.c2 * (yx - m.qx) + m.s2 * (yy - m.qy);
  const auto u1 = w.U1.head(n), u2 = w.U2.head(n);
  w.Z.head(n) = m.k * u1;
  erf_and_gauss(w.Z, n, w.E1, w.G1);
  w.Z.head(n) = m.k * u2;
  erf_and_gauss(w.Z, n, w.E2, w.G2);
  w.S.head(n) = w.E1.head(n) * w.E2.head(n);
}

// The normal equations Jw' J and Jw' y of the first K columns. One pass over the pixels per row
// of Jw' J, all of that row's sums in registers at once: the 9 (not 54) passes halve the loads
// and drop the 54 horizontal reductions of separate dot products (~1/4 of a tracked frame's time).
// Four-float vectors (GCC vector extension: SSE2, the x86-64 baseline); the arrays' tails up to
// the next multiple of 4 are zeroed first so that whole vectors can be read.
using V4 = float __attribute__((vector_size(16)));
inline V4 load4(const float* p) {
  V4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline double sum4(V4 v) {
  return static_cast<double>((v[0] + v[1]) + (v[2] + v[3]));
}

template <int K, int A>
void normal_row(const std::array<const float*, K + 1>& cols, const float* jw, int n4, MatK<K>& JtJ,
                VecK<K>& Jty) {
  constexpr int m = K + 1 - A;  // columns A..K-1 and y
  V4 acc[m] = {};
  for (int i = 0; i < n4; i += 4) {
    const V4 x = load4(jw + i);
#pragma GCC unroll 12
    for (int b = 0; b < m; ++b) acc[b] += x * load4(cols[static_cast<std::size_t>(A + b)] + i);
  }
  for (int b = 0; b + 1 < m; ++b) JtJ(A, A + b) = JtJ(A + b, A) = sum4(acc[b]);
  Jty[A] = sum4(acc[m - 1]);
}

template <int K>
void normal_equations(FastFitScratch& w, int n, float* y, MatK<K>& JtJ, VecK<K>& Jty) {
  const int n4 = (n + 3) & ~3;
  std::array<const float*, K + 1> cols;
  for (int b = 0; b < K; ++b) {
    const auto k = static_cast<std::size_t>(b);
    for (int i = n; i < n4; ++i) w.J[k][i] = w.Jw[k][i] = 0.0f;
    cols[k] = w.J[k].data();
  }
  for (int i = n; i < n4; ++i) y[i] = 0.0f;
  cols[K] = y;
  [&]<int... A>(std::integer_sequence<int, A...>) {
    (normal_row<K, A>(cols, w.Jw[static_cast<std::size_t>(A)].data(), n4, JtJ, Jty), ...);
  }
  (std::make_integer_sequence<int, K>{});
}

// The weighted cost at p and, with JtJ set, the normal equations of the active parameters.
// `shape_ready`: shape() was already run at this p.
template <int K>
double evaluate(FastFitScratch& w, int n, const Vec& p, const std::array<int, 11>* active, MatK<K>* JtJ,
                VecK<K>* Jtr, bool shape_ready = false) {
  constexpr int n_active = K;
  const Model m(p);
  const auto yx = w.yx.head(n), yy = w.yy.head(n), dx = w.dx.head(n), dy = w.dy.head(n);
  const auto u1 = w.U1.head(n), u2 = w.U2.head(n);
  if (!shape_ready) shape(w, n, m);
  w.C.head(n) = m.b + m.hx * dx + m.hy * dy;
  w.r.head(n) = m.a + m.gx * dx + m.gy * dy + w.C.head(n) * w.S.head(n) - w.val.head(n);
  const double cost = static_cast<double>((w.wt.head(n) * w.r.head(n).square()).sum());
  if (!JtJ) return cost;
  constexpr float kTwoOverSqrtPi = 1.12837916709551257390f;
  // A = C dS/du1, B = C dS/du2 (kept in G1, G2).
  w.G1.head(n) *= (kTwoOverSqrtPi * m.k) * w.C.head(n) * w.E2.head(n);
  w.G2.head(n) *= (kTwoOverSqrtPi * m.k) * w.C.head(n) * w.E1.head(n);
  const auto A = w.G1.head(n), B = w.G2.head(n), S = w.S.head(n);
  for (int j = 0; j < n_active; ++j) {
    Arr& col = w.J[static_cast<std::size_t>(j)];
    switch ((*active)[static_cast<std::size_t>(j)]) {
      case 0:
        col.head(n) = -(A * m.c1 + B * m.c2);
        break;
      case 1:
        col.head(n) = -(A * m.s1 + B * m.s2);
        break;
      case 2:
        col.head(n) = A * (-m.s1 * (yx - m.qx) + m.c1 * (yy - m.qy));
        break;
      case 3:
        col.head(n) = B * (-m.s2 * (yx - m.qx) + m.c2 * (yy - m.qy));
        break;
      case 4:
        col.head(n) = -(A * u1 + B * u2) * m.inv_s;
        break;
      case 5:
        col.head(n).setOnes();
        break;
      case 6:
        col.head(n) = dx;
        break;
      case 7:
        col.head(n) = dy;
        break;
      case 8:
        col.head(n) = S;
        break;
      case 9:
        col.head(n) = dx * S;
        break;
      default:
        col.head(n) = dy * S;
        break;
    }
    w.Jw[static_cast<std::size_t>(j)].head(n) = w.wt.head(n) * col.head(n);
  }
  normal_equations<K>(w, n, w.r.data(), *JtJ, *Jtr);
  return cost;
}

// The six shading terms are linear for a fixed geometry: initialise them by linear least squares.
void init_linear(FastFitScratch& w, int n, Vec& p) {
  shape(w, n, Model(p));
  const auto dx = w.dx.head(n), dy = w.dy.head(n);
  const auto S = w.S.head(n);
  w.J[0].head(n).setOnes();
  w.J[1].head(n) = dx;
  w.J[2].head(n) = dy;
  w.J[3].head(n) = S;
  w.J[4].head(n) = dx * S;
  w.J[5].head(n) = dy * S;
  Eigen::Matrix<double, 6, 6> M;
  Eigen::Matrix<double, 6, 1> rhs;
  for (std::size_t a = 0; a < 6; ++a) {
    w.Jw[a].head(n) = w.wt.head(n) * w.J[a].head(n);
    rhs[static_cast<int>(a)] = static_cast<double>((w.Jw[a].head(n) * w.val.head(n)).sum());
    for (std::size_t b = 0; b <= a; ++b) {
      const double v = static_cast<double>((w.Jw[a].head(n) * w.J[b].head(n)).sum());
      M(static_cast<int>(a), static_cast<int>(b)) = v;
      M(static_cast<int>(b), static_cast<int>(a)) = v;
    }
  }
  M.diagonal().array() += 1e-9 * (M.diagonal().maxCoeff() + 1.0);
  p.segment<6>(5) = M.ldlt().solve(rhs);
}

// `shape_ready`: shape() was run at p (by init_linear). Returns the iterations, `cost` the final cost.
template <int K>
int levenberg_marquardt(FastFitScratch& w, int n, Vec& p, const std::array<int, 11>& active,
                        int max_iterations, double tolerance_px, double trust_px, double lambda,
                        bool shape_ready, double& cost) {
  constexpr int n_active = K;
  MatK<K> JtJ, JtJ2;
  VecK<K> Jtr, Jtr2;
  cost = evaluate<K>(w, n, p, &active, &JtJ, &Jtr, shape_ready);
  int it = 0;
  for (; it < max_iterations; ++it) {
    MatK<K> A = JtJ;
    A.diagonal() += lambda * JtJ.diagonal().cwiseMax(1e-12);
    const VecK<K> step = -A.ldlt().solve(Jtr);
    if (!step.allFinite()) break;
    Vec cand = p;
    for (int j = 0; j < n_active; ++j) cand[active[static_cast<std::size_t>(j)]] += step[j];
    if (!(cand[4] > 0.05)) cand[4] = 0.05;
    // A short Gauss-Newton step is taken without evaluating the model at its end: from a start
    // (position and blur) within kTrustStepPx of the optimum Gauss-Newton lands
    // within ~1e-3 px of it, far below the corner noise (measured on bench_corners' 48 eyes: RMS
    // against the truth 0.01438 px this way, 0.01442 px iterating to 1e-3 px, 1.5x faster). The
    // cost is the linear model's prediction, cost + 2 s.Jtr + s' JtJ s.
    double blur_step = 0;  // the other nonlinear parameter: a start with a wrong blur needs iterations
    for (int j = 0; j < n_active; ++j)
      if (active[static_cast<std::size_t>(j)] == 4) blur_step = std::abs(step[j]);
    if (lambda <= 1e-3 && step.template head<2>().norm() < std::max(trust_px, tolerance_px) &&
        blur_step < trust_px) {
      p = cand;
      cost = std::max(0.0, cost + 2.0 * step.dot(Jtr) + step.dot(JtJ * step));
      break;
    }
    const double c2 = evaluate<K>(w, n, cand, &active, &JtJ2, &Jtr2);
    if (c2 < cost) {
      p = cand;
      JtJ = JtJ2;
      Jtr = Jtr2;
      cost = c2;
      lambda = std::max(lambda * 0.2, 1e-9);
      if (step.template head<2>().norm() < tolerance_px) break;
    } else {
      lambda *= 10.0;
      if (lambda > 1e8) break;
    }
  }
  return it + 1;
}

}  // namespace

FastFitScratch::FastFitScratch() {
  for (Arr* a : {&dx, &dy, &yx, &yy, &val, &wt, &r, &E1, &E2, &G1, &G2, &S, &C, &U1, &U2, &Z})
    a->setZero(kMaxPixels);
  for (std::size_t i = 0; i < J.size(); ++i) {
    J[i].setZero(kMaxPixels);
    Jw[i].setZero(kMaxPixels);
  }
}

bool fit_saddle_fast(const LumaView& img, const CameraModel& cam, const UndistortMap& map,
                     const SaddleInit& init, const EdgeDirections* edges, double radius, int max_iterations,
                     double tolerance_px, FastFitScratch& w, SaddleFit& out) {
  constexpr double kHalfPi = 1.57079632679489661923;
  out = SaddleFit{};
  const int half = static_cast<int>(std::ceil(radius)) + 1;
  if (radius < 1.5 || half > FastFitScratch::kMaxHalf) return false;
  const int cx = static_cast<int>(std::lround(init.px.x())), cy = static_cast<int>(std::lround(init.px.y()));
  if (cx - half < 0 || cx + half >= img.col_end || cy - half < img.row_begin || cy + half >= img.row_end) {
    return false;
  }
  // Local undistorted coordinates y = Jp (x(p) - x(c)), Jp = d pixel / d normalized at the centre:
  // y ~ p - c to first order and the board's edges are straight lines in y (see corners_refine.hpp).
  // The window's rows of the table and of the image are rarely in cache (two cameras' tables are
  // ~1 MB): ask for all of them before the first is needed.
  for (int r = -half; r <= half; ++r) {
    const auto i = static_cast<std::size_t>((cy + r) * map.width() + cx - half);
    const float* t = map.xy_data() + 2 * i;
    __builtin_prefetch(t);
    __builtin_prefetch(t + 16);
    __builtin_prefetch(t + 2 * (2 * half));
    __builtin_prefetch(img.data + static_cast<std::size_t>((cy + r) * img.width + cx - half));
    __builtin_prefetch(img.data + static_cast<std::size_t>((cy + r) * img.width + cx + half));
  }
  float x0f = 0, y0f = 0;
  bool undist = map.at(cx, cy, x0f, y0f);
  for (int r = -half; r <= half && undist; ++r) {
    const unsigned char* v = map.valid_data() + (cy + r) * map.width() + cx - half;
    undist = std::memchr(v, 0, static_cast<std::size_t>(2 * half + 1)) == nullptr;
  }
  const Eigen::Vector2d x0(x0f, y0f);
  Eigen::Matrix2d Jp = Eigen::Matrix2d::Identity();
  if (undist) {
    Eigen::Matrix2d Kaff;
    Kaff << cam.fx(), cam.skew(), 0.0, cam.fy();
    Jp = Kaff * cam.distort_jacobian(x0);
  }
  const Eigen::Matrix2f Jf = Jp.cast<float>();
  const Eigen::Vector2d off = init.px - Eigen::Vector2d(cx, cy);
  const float inv_half = 1.0f / static_cast<float>(half);
  // Weight 1 up to `radius` (Chebyshev from the start), a 1 px linear taper beyond: the fit varies
  // continuously with where it starts, so tracking and full search agree. The Chebyshev weight is
  // separable, min(row weight, column weight), and each is positive on one contiguous run.
  std::array<float, 2 * FastFitScratch::kMaxHalf + 1> wcol{}, wrow{};
  auto taper = [&](int k, double o) {
    return static_cast<float>(std::clamp(radius + 0.5 - std::abs(k - o), 0.0, 1.0));
  };
  int q0 = half + 1, q1 = -half - 1;
  for (int k = -half; k <= half; ++k) {
    const auto i = static_cast<std::size_t>(k + half);
    wcol[i] = taper(k, off.x());
    wrow[i] = taper(k, off.y());
    if (wcol[i] > 0.0f) {
      q0 = std::min(q0, k);
      q1 = std::max(q1, k);
    }
  }
  float *dx = w.dx.data(), *dy = w.dy.data(), *wyx = w.yx.data(), *wyy = w.yy.data(), *val = w.val.data(),
        *wt = w.wt.data();
  const float j00 = Jf(0, 0), j01 = Jf(0, 1), j10 = Jf(1, 0), j11 = Jf(1, 1);
  int n = 0;
  for (int r = -half; r <= half; ++r) {
    const float wr = wrow[static_cast<std::size_t>(r + half)];
    if (!(wr > 0.0f)) continue;
    const std::size_t row = static_cast<std::size_t>(cy + r) * static_cast<std::size_t>(map.width()) +
                            static_cast<std::size_t>(cx);
    const float* mxy = map.xy_data() + 2 * row;
    const float* im = img.data + static_cast<std::size_t>(cy + r) * static_cast<std::size_t>(img.width) +
                      static_cast<std::size_t>(cx);
    const float fr = static_cast<float>(r) * inv_half;
    for (int q = q0; q <= q1; ++q, ++n) {
      float yx = static_cast<float>(q), yy = static_cast<float>(r);
      if (undist) {
        const float ux = mxy[2 * q] - x0f, uy = mxy[2 * q + 1] - y0f;
        yx = j00 * ux + j01 * uy;
        yy = j10 * ux + j11 * uy;
      }
      dx[n] = static_cast<float>(q) * inv_half;
      dy[n] = fr;
      wyx[n] = yx;
      wyy[n] = yy;
      val[n] = im[q];
      wt[n] = std::min(wr, wcol[static_cast<std::size_t>(q + half)]);
    }
  }

  Vec p;
  // y = p - c to first order: the start needs no more.
  p << off.x(), off.y(), init.theta1, init.theta2, init.sigma, 0, 0, 0, 0, 0, 0;
  if (edges) {
    Eigen::Vector2d t1 = edges->row_px, t2 = edges->col_px;
    if (undist && edges->normalized_ok) {
      t1 = Jp * edges->row_n;
      t2 = Jp * edges->col_n;
    }
    p[2] = std::atan2(t1.y(), t1.x()) + kHalfPi;
    p[3] = std::atan2(t2.y(), t2.x()) + kHalfPi;
  }
  const double h = half;
  const Eigen::Vector2d centre(cx, cy);
  if (init.shading.valid) {
    // The linear terms of a previous fit of this corner, moved to this window (the model is linear
    // in them, so the first Gauss-Newton step solves them exactly whatever their start): no
    // separate linear solve.
    const SaddleShading& sh = init.shading;
    const Eigen::Vector2d d = centre - init.shading_at;
    p.segment<6>(5) << sh.a + sh.gx * d.x() + sh.gy * d.y(), sh.gx * h, sh.gy * h,
        sh.b + sh.hx * d.x() + sh.hy * d.y(), sh.hx * h, sh.hy * h;
  } else {
    init_linear(w, n, p);
  }
  // With the edges fixed the problem is nearly linear around a close start: (almost) Gauss-Newton.
  double cost = 0;
  const bool shaped = !init.shading.valid;
  out.iterations =
      edges ? levenberg_marquardt<9>(w, n, p, kFixedEdges, max_iterations, tolerance_px, kTrustStepPx, 1e-6,
                                     shaped, cost)
            : levenberg_marquardt<11>(w, n, p, kFull, max_iterations, tolerance_px, 0.0, 1e-3, shaped, cost);
  const double used = static_cast<double>(w.wt.head(n).sum());
  out.theta1 = p[2];
  out.theta2 = p[3];
  out.sigma = p[4];
  out.contrast = std::abs(p[8]);
  out.rms = std::sqrt(cost / std::max(1.0, used));
  out.undistorted = undist;
  const Eigen::Vector2d q(p[0], p[1]);
  if (!p.allFinite() || q.cwiseAbs().maxCoeff() > half) return false;
  if (std::abs(std::sin(p[2] - p[3])) < 0.3) return false;  // edges (nearly) parallel: not a corner
  if (undist) {
    out.px = cam.to_pixel(cam.distort(x0 + Jp.inverse() * q));
  } else {
    out.px = Eigen::Vector2d(cx, cy) + q;
  }
  // The linear terms referred to the corner, gradients per raw pixel.
  const Eigen::Vector2d d = (out.px - centre) / h;
  out.shading = SaddleShading{p[5] + p[6] * d.x() + p[7] * d.y(),
                              p[6] / h,
                              p[7] / h,
                              p[8] + p[9] * d.x() + p[10] * d.y(),
                              p[9] / h,
                              p[10] / h,
                              true};
  out.converged = true;
  return true;
}

}  // namespace naneye::recon
