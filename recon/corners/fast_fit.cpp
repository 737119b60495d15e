#include "naneye/recon/corners/fast_fit.hpp"

#include "naneye/recon/corners/noise.hpp"

#include "simd.hpp"

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
constexpr double kOutlierCheckRelative = 0.05;  // see the outlier check in fit_saddle_fast
constexpr int kMaxOutliers = 4;
// A blurred edge reaches 2.5 sigma (erf 0.9996 of its step) into the window; the fitted blur is at
// least the lens's (the real NanEye's ~1 px, the simulator's 0.3-0.4 px), taken as 0.5 px when the
// start knows none better.
constexpr double kBlurReach = 2.5;
constexpr double kMinBlurForReachPx = 0.5;
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

// The model's parameters as the vector kernels take them (float, the normals as cosines and sines).
simd::ModelParams model_params(const Vec& p) {
  return {float(p[0]),
          float(p[1]),
          float(std::cos(p[2])),
          float(std::sin(p[2])),
          float(std::cos(p[3])),
          float(std::sin(p[3])),
          float(0.70710678118654752440 / p[4]),
          float(1.0 / p[4]),
          float(p[5]),
          float(p[6]),
          float(p[7]),
          float(p[8]),
          float(p[9]),
          float(p[10])};
}

// The geometry part of the model at p: u1, u2, S and the factors of its derivatives (corners/simd.hpp).
void shape(FastFitScratch& w, int n, const simd::ModelParams& m) {
  (w.use_avx2 ? simd::shape_avx2 : simd::shape_sse)(m, w.yx.data(), w.yy.data(), n, w.U1.data(), w.U2.data(),
                                                    w.E1.data(), w.E2.data(), w.G1.data(), w.G2.data(),
                                                    w.S.data());
}

// The normal equations Jw' J and Jw' y of the first K columns of J (y: the residual, or the data for
// the linear start), in one pass over the pixels per row (corners/simd.hpp): ~1/4 of a tracked
// frame's time as K (K + 3) / 2 separate dot products. The tails up to a whole number of 8-float
// vectors are zeroed first.
template <int K>
void normal_equations(FastFitScratch& w, int n, float* y, MatK<K>& JtJ, VecK<K>& Jty) {
  const int nv = (n + 7) & ~7;
  std::array<const float*, K + 1> cols;
  std::array<const float*, K> jw;
  for (int b = 0; b < K; ++b) {
    const auto k = static_cast<std::size_t>(b);
    for (int i = n; i < nv; ++i) w.J[k][i] = w.Jw[k][i] = 0.0f;
    cols[k] = w.J[k].data();
    jw[k] = w.Jw[k].data();
  }
  for (int i = n; i < nv; ++i) y[i] = 0.0f;
  cols[K] = y;
  std::array<double, (K + 1) * K> out;
  if (w.use_avx2) {
    simd::normal_equations_avx2<K>(cols, jw, nv, out);
  } else {
    simd::normal_equations_sse<K>(cols, jw, nv, out);
  }
  for (int a = 0; a < K; ++a) {
    for (int b = a; b < K; ++b) JtJ(a, b) = JtJ(b, a) = out[static_cast<std::size_t>(a * (K + 1) + b)];
    Jty[a] = out[static_cast<std::size_t>(a * (K + 1) + K)];
  }
}

// The weighted cost at p and the normal equations of the K active parameters: K = 9 with the edge
// normals fixed, 11 with all parameters (kFixedEdges / kFull order). `shape_ready`: shape() was
// already run at this p.
template <int K>
double evaluate(FastFitScratch& w, int n, const Vec& p, MatK<K>& JtJ, VecK<K>& Jtr,
                bool shape_ready = false) {
  static_assert(K == 9 || K == 11);
  const simd::ModelParams m = model_params(p);
  if (!shape_ready) shape(w, n, m);
  const simd::WindowArrays in{w.yx.data(), w.yy.data(), w.dx.data(), w.dy.data(), w.val.data(),
                              w.wt.data(), w.U1.data(), w.U2.data(), w.E1.data(), w.E2.data(),
                              w.G1.data(), w.G2.data(), w.S.data()};
  std::array<float*, 11> J{}, Jw{};
  for (std::size_t c = 0; c < 11; ++c) {
    J[c] = w.J[c].data();
    Jw[c] = w.Jw[c].data();
  }
  const int nv = (n + 7) & ~7;  // the window's tails hold zero weight (fit_saddle_fast)
  constexpr bool free_edges = K == 11;
  const double cost = w.use_avx2 ? simd::residuals_jacobian_avx2<free_edges>(m, in, nv, w.r.data(), J, Jw)
                                 : simd::residuals_jacobian_sse<free_edges>(m, in, nv, w.r.data(), J, Jw);
  normal_equations<K>(w, n, w.r.data(), JtJ, Jtr);
  return cost;
}

// The six shading terms are linear for a fixed geometry: initialise them by linear least squares.
void init_linear(FastFitScratch& w, int n, Vec& p) {
  shape(w, n, model_params(p));
  const auto dx = w.dx.head(n), dy = w.dy.head(n);
  const auto S = w.S.head(n);
  w.J[0].head(n).setOnes();
  w.J[1].head(n) = dx;
  w.J[2].head(n) = dy;
  w.J[3].head(n) = S;
  w.J[4].head(n) = dx * S;
  w.J[5].head(n) = dy * S;
  for (std::size_t a = 0; a < 6; ++a) w.Jw[a].head(n) = w.wt.head(n) * w.J[a].head(n);
  MatK<6> M;
  VecK<6> rhs;
  normal_equations<6>(w, n, w.val.data(), M, rhs);
  M.diagonal().array() += 1e-9 * (M.diagonal().maxCoeff() + 1.0);
  p.segment<6>(5) = M.ldlt().solve(rhs);
}

// `shape_ready`: shape() was run at p (by init_linear). Returns the iterations, `cost` the final cost.
template <int K>
int levenberg_marquardt(FastFitScratch& w, int n, Vec& p, const std::array<int, 11>& active,
                        int max_iterations, double tolerance_px, double trust_px, double lambda,
                        bool shape_ready, double& cost, double& position_var) {
  constexpr int n_active = K;
  MatK<K> JtJ, JtJ2;
  VecK<K> Jtr, Jtr2;
  cost = evaluate<K>(w, n, p, JtJ, Jtr, shape_ready);
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
    const double c2 = evaluate<K>(w, n, cand, JtJ2, Jtr2);
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
  // The position block of the normal equations' inverse (the corner is parameters 0 and 1 in both
  // orders), at the last point where they were formed: within the last short step of the solution.
  const MatK<K> inv = JtJ.ldlt().solve(MatK<K>::Identity());
  const Eigen::Matrix2d cq = inv.template topLeftCorner<2, 2>();
  const double mid = 0.5 * (cq(0, 0) + cq(1, 1)), det = cq(0, 0) * cq(1, 1) - cq(0, 1) * cq(1, 0);
  position_var = mid + std::sqrt(std::max(mid * mid - det, 0.0));
  return it + 1;
}

}  // namespace

FastFitScratch::FastFitScratch() : use_avx2(simd::has_avx2_fma()) {
  for (Arr* a : {&dx, &dy, &yx, &yy, &val, &wt, &r, &E1, &E2, &G1, &G2, &S, &U1, &U2}) a->setZero(kMaxPixels);
  for (std::size_t i = 0; i < J.size(); ++i) {
    J[i].setZero(kMaxPixels);
    Jw[i].setZero(kMaxPixels);
  }
}

bool load_fit_window(const LumaView& img, const CameraModel& cam, const UndistortMap& map,
                     const Eigen::Vector2d& px, double radius, FastFitScratch& w, FitWindow& win) {
  const int half = static_cast<int>(std::ceil(radius)) + 1;
  if (radius < 1.5 || half > FastFitScratch::kMaxHalf) return false;
  const int cx = static_cast<int>(std::lround(px.x())), cy = static_cast<int>(std::lround(px.y()));
  if (cx - half < 0 || cx + half >= img.col_end || cy - half < img.row_begin || cy + half >= img.row_end) {
    return false;
  }
  // Local undistorted coordinates y = Jp (x(p) - x(c)), Jp = d pixel / d normalized at the centre:
  // y ~ p - c to first order and the board's edges are straight lines in y (see corners/refine.hpp).
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
  const Eigen::Vector2d off = px - Eigen::Vector2d(cx, cy);
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
    const std::uint8_t* clip =
        img.clipped ? img.clipped + static_cast<std::size_t>(cy + r) * static_cast<std::size_t>(img.width) +
                          static_cast<std::size_t>(cx)
                    : nullptr;
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
      // A clipped pixel only says the light was at least full scale: it takes no part in the fit.
      wt[n] = im[q] >= kClipDn || (clip && clip[q]) ? 0.0f
                                                    : std::min(wr, wcol[static_cast<std::size_t>(q + half)]);
    }
  }

  // Whole vectors are read past n (corners/simd.hpp): the tail pixels get zero weight.
  for (int i = n; i < ((n + 7) & ~7); ++i) dx[i] = dy[i] = wyx[i] = wyy[i] = val[i] = wt[i] = 0.0f;

  win = FitWindow{n, cx, cy, half, undist, x0, off, Jp};
  return true;
}

bool fit_saddle_fast(const LumaView& img, const CameraModel& cam, const UndistortMap& map,
                     const SaddleInit& init, const EdgeDirections* edges, double radius, int max_iterations,
                     double tolerance_px, FastFitScratch& w, SaddleFit& out) {
  constexpr double kHalfPi = 1.57079632679489661923;
  out = SaddleFit{};
  FitWindow win;
  if (!load_fit_window(img, cam, map, init.px, radius, w, win)) return false;
  const int n = win.n, cx = win.cx, cy = win.cy, half = win.half;
  const bool undist = win.undistorted;
  const Eigen::Vector2d off = win.off;
  const Eigen::Matrix2d Jp = win.Jp;
  float *wyx = w.yx.data(), *wyy = w.yy.data(), *wt = w.wt.data();

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
    // The model holds one X-junction: the square window must not reach the next grid lines, which on
    // a skewed grid (edges ~45 degrees apart at steep tilts) lie nearer than the window's corners
    // along the edge normals. Pixels within kBlurReach blurs of a next line lose their weight (1 px
    // taper), the others stay: the window keeps its length along the edges, which hold the corner.
    if (edges->row_line_px > 0 && edges->col_line_px > 0) {
      const double s_blur = std::max(init.sigma, kMinBlurForReachPx);
      const float lim1 = static_cast<float>(edges->row_line_px - kBlurReach * s_blur);
      const float lim2 = static_cast<float>(edges->col_line_px - kBlurReach * s_blur);
      const float c1 = static_cast<float>(std::cos(p[2])), s1 = static_cast<float>(std::sin(p[2]));
      const float c2 = static_cast<float>(std::cos(p[3])), s2 = static_cast<float>(std::sin(p[3]));
      const float ox = static_cast<float>(off.x()), oy = static_cast<float>(off.y());
      for (int i = 0; i < n; ++i) {
        const float x = wyx[i] - ox, y = wyy[i] - oy;
        const float a1 = std::abs(c1 * x + s1 * y), a2 = std::abs(c2 * x + s2 * y);
        wt[i] *= std::clamp(lim1 + 0.5f - a1, 0.0f, 1.0f) * std::clamp(lim2 + 0.5f - a2, 0.0f, 1.0f);
      }
    }
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
  double cost = 0, position_var = 0;
  const bool shaped = !init.shading.valid;
  auto fit = [&](bool shape_ready) {
    return edges ? levenberg_marquardt<9>(w, n, p, kFixedEdges, max_iterations, tolerance_px, kTrustStepPx,
                                          1e-6, shape_ready, cost, position_var)
                 : levenberg_marquardt<11>(w, n, p, kFull, max_iterations, tolerance_px, 0.0, 1e-3,
                                           shape_ready, cost, position_var);
  };
  out.iterations = fit(shaped);
  double used = static_cast<double>(w.wt.head(n).sum());
  // A defect pixel the luminance's repair cannot see (a hot or dead pixel on an edge lies between its
  // neighbours' values, not beyond all of them) adds ~30 DN to the RMS of a 15 x 15 window: enough to
  // reject the corner (3 of the study's 57 boards). A window whose fit is poorer than
  // almost any other (RMS > 5 % of the contrast: the 99.9th percentile of normal corners is ~3.7 %)
  // gets its residuals checked; up to kMaxOutliers pixels beyond 4x the RMS and 30 % of the contrast
  // lose their weight and the fit runs again from where it is.
  if (p.allFinite() && std::sqrt(cost / std::max(1.0, used)) > kOutlierCheckRelative * std::abs(p[8])) {
    if (edges) {
      MatK<9> A;
      VecK<9> b;
      cost = evaluate<9>(w, n, p, A, b);
    } else {
      MatK<11> A;
      VecK<11> b;
      cost = evaluate<11>(w, n, p, A, b);
    }
    const float limit =
        static_cast<float>(std::max(4.0 * std::sqrt(cost / std::max(1.0, used)), 0.3 * std::abs(p[8])));
    int count = 0;
    for (int i = 0; i < n; ++i) count += w.wt[i] > 0.0f && std::abs(w.r[i]) > limit;
    if (count > 0 && count <= kMaxOutliers) {
      for (int i = 0; i < n; ++i)
        if (std::abs(w.r[i]) > limit) w.wt[i] = 0.0f;
      out.outliers = count;
      out.iterations += fit(false);
      used = static_cast<double>(w.wt.head(n).sum());
    }
  }
  out.theta1 = p[2];
  out.theta2 = p[3];
  out.sigma = p[4];
  out.contrast = std::abs(p[8]);
  out.rms = std::sqrt(cost / std::max(1.0, used));
  out.weight = used;
  out.position_var_per_noise = std::isfinite(position_var) ? position_var : 1e30;
  out.undistorted = undist;
  const Eigen::Vector2d q(p[0], p[1]);
  if (!p.allFinite() || q.cwiseAbs().maxCoeff() > half) return false;
  if (std::abs(std::sin(p[2] - p[3])) < 0.3) return false;  // edges (nearly) parallel: not a corner
  place_corner(win, cam, q, p.data() + 5, out);
  out.converged = true;
  return true;
}

void place_corner(const FitWindow& win, const CameraModel& cam, const Eigen::Vector2d& q, const double* lin,
                  SaddleFit& out) {
  const Eigen::Vector2d centre(win.cx, win.cy);
  out.px = win.undistorted ? cam.to_pixel(cam.distort(win.x0 + win.Jp.inverse() * q)) : centre + q;
  const double h = win.half;
  const Eigen::Vector2d d = (out.px - centre) / h;
  out.shading = SaddleShading{lin[0] + lin[1] * d.x() + lin[2] * d.y(),
                              lin[1] / h,
                              lin[2] / h,
                              lin[3] + lin[4] * d.x() + lin[5] * d.y(),
                              lin[4] / h,
                              lin[5] / h,
                              true};
}

}  // namespace naneye::recon
