// Inverse-compositional affine Lucas-Kanade (lk_affine.hpp).
#include "naneye/recon/scene/lk_affine.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>

#include "../corners/simd.hpp"
#include "lk_dots.hpp"
#include "lk_sample.hpp"
#include "lk_window.hpp"
#include "naneye/recon/scene/bspline.hpp"
#include "round.hpp"
#include "spd_factor.hpp"

namespace naneye::recon::scene {
namespace {

using lk_window::dot_gram;
using lk_window::gram;
using lk_window::kernel_gram;
using lk_window::kernel_outer;
using lk_window::kMaxN;
using lk_window::kMaxN8;
using lk_window::monomials;
using lk_window::multiply;
using lk_window::project;

// Rows 4 and 5 of the inverse of a factored symmetric 6 x 6 (its columns 4 and 5, transposed):
// the translation's part of a solve.
Eigen::Matrix<double, 2, 6> translation_rows(const SpdFactor<6>& f) {
  Eigen::Matrix<double, 2, 6> p;
  p.row(0) = f.solve(Eigen::Matrix<double, 6, 1>::Unit(4)).transpose();
  p.row(1) = f.solve(Eigen::Matrix<double, 6, 1>::Unit(5)).transpose();
  return p;
}

// Variance of a central-difference gradient, (x[+1] - x[-1]) / 2, of noise filtered by the 3 x 3
// kernel b, per unit of the filtered noise's own variance: 1/2 for white noise.
double gradient_noise_ratio(const std::array<float, 9>& b) {
  double g2 = 0, b2 = 0;
  for (int r = 0; r < 3; ++r)
    for (int c = -1; c <= 3; ++c) {  // (b * d)(r, c), d = [-1/2 0 1/2] along the row
      const auto at = [&](int cc) {
        return cc < 0 || cc > 2 ? 0.0 : double(b[static_cast<std::size_t>(r * 3 + cc)]);
      };
      const double v = 0.5 * (at(c - 1) - at(c + 1));
      g2 += v * v;
    }
  for (float x : b) b2 += double(x) * x;
  return g2 / b2;
}

// sum u u^T, u = (x, y, 1), from the sums of x^2, x y, y^2, x, y, 1.
Eigen::Matrix3d moment_matrix(const std::array<double, 6>& m) {
  Eigen::Matrix3d u;
  u << m[0], m[1], m[3], m[1], m[2], m[4], m[3], m[4], m[5];
  return u;
}

}  // namespace

double noise_dof_factor(const std::array<float, 9>& b) {
  // The noise's autocorrelation is the kernel's with itself, lags -2..2 in both directions.
  double acf[5][5] = {};
  for (int i = 0; i < 9; ++i)
    for (int j = 0; j < 9; ++j) acf[j / 3 - i / 3 + 2][j % 3 - i % 3 + 2] += double(b[i]) * b[j];
  double sum = 0;
  for (const auto& row : acf)
    for (double a : row) sum += (a / acf[2][2]) * (a / acf[2][2]);
  return sum;
}

LkResult refine_affine(const GrayView& src, const float* tgx, const float* tgy, int u, int v,
                       const GrayView& dst, const std::uint8_t* dst_usable, const Eigen::Vector2d& start,
                       const Eigen::Matrix2d& A0, const Eigen::Vector2d* shape, const LkSettings& s,
                       const Eigen::Matrix2d* start_linear) {
  LkResult out;
  const int rad = s.radius, side = 2 * rad + 1, n = side * side;
  if (rad < 1 || n > kMaxN) return out;  // rad 1: 9 pixels, one more than the fit's 8 parameters
  const int n8 = lk_dots::padded(n);
  // Template, normalised to zero mean and unit norm (and its gradients by the same scale). t and the
  // steepest-descent images as float arrays for lk_dots, zero beyond n.
  alignas(32) float t[kMaxN8];
  alignas(32) float sdf[6][kMaxN8];
  alignas(32) float sd_in[6][kMaxN8];  // sdf on the inner pixels, 0 on the ring (inner_radius only)
  alignas(32) float ones[kMaxN8], inner[kMaxN8];  // 1 on the window (its inner pixels), else 0
  // The warp's domain: the template pixels themselves, or their predicted places in the target
  // (`shape`), where the template's gradient is d T / d q = d T / d x * A0^-1 (A0 varies little over
  // the window; a gradient slightly off only slows convergence, the fixed point stays).
  alignas(32) float qx[kMaxN8], qy[kMaxN8];
  alignas(32) float gx[kMaxN8], gy[kMaxN8];  // the template's raw gradients
  double mean = 0;
  for (int dr = -rad, k = 0; dr <= rad; ++dr)
    for (int dc = -rad; dc <= rad; ++dc, ++k) {
      const std::size_t p = static_cast<std::size_t>(v + dr) * src.width + u + dc;
      mean += t[k] = src.data[p];
      qx[k] = shape ? static_cast<float>(shape[k].x()) : static_cast<float>(dc);
      qy[k] = shape ? static_cast<float>(shape[k].y()) : static_cast<float>(dr);
      gx[k] = tgx[p];
      gy[k] = tgy[p];
    }
  for (int k = n; k < n8; ++k) t[k] = qx[k] = qy[k] = gx[k] = gy[k] = 0.f;
  // The masks by rows (a per-pixel test of the ring cost ~2 % of the sparse path).
  std::fill(ones, ones + n, 1.f);
  std::fill(ones + n, ones + n8, 0.f);
  std::fill(inner, inner + n8, 0.f);
  if (s.inner_radius > 0) {
    const int ri = std::min(s.inner_radius, rad);
    for (int dr = -ri; dr <= ri; ++dr) {
      float* centre_of_row = inner + (dr + rad) * side + rad;
      std::fill(centre_of_row - ri, centre_of_row + ri + 1, 1.f);
    }
  }
  mean /= n;
  double ss = 0;
  for (int k = 0; k < n; ++k) ss += (t[k] - mean) * (t[k] - mean);
  if (!(ss > 0)) return out;
  const double scale = 1.0 / std::sqrt(ss);
  for (int k = 0; k < n; ++k) t[k] = static_cast<float>((t[k] - mean) * scale);
  const Eigen::Matrix2d to_q = shape ? Eigen::Matrix2d(A0.inverse()) : Eigen::Matrix2d::Identity();
  // d W / d p at q for W(q) = (I + [p0 p1; p2 p3]) q + (p4, p5): sd = (gqx qx, gqx qy, gqy qx, gqy qy,
  // gqx, gqy) with the gradient in q, gq = scale (gx, gy) to_q. Over whole blocks (zero padding stays
  // zero), in vectors.
  const Eigen::Matrix2f G = (scale * to_q).cast<float>();
  {
    using simd::V4;
    // splat keeps a -0 (A0's inverse has them): the scalar loop's products to the sign of a zero.
    const V4 g00 = simd::splat<V4>(G(0, 0)), g10 = simd::splat<V4>(G(1, 0)), g01 = simd::splat<V4>(G(0, 1)),
             g11 = simd::splat<V4>(G(1, 1));
    for (int k = 0; k < n8; k += 4) {
      const V4 x = simd::load<V4>(gx + k), y = simd::load<V4>(gy + k);
      const V4 a = x * g00 + y * g10, b = x * g01 + y * g11;
      const V4 cx = simd::load<V4>(qx + k), cy = simd::load<V4>(qy + k);
      simd::store(&sdf[0][k], a * cx);
      simd::store(&sdf[1][k], a * cy);
      simd::store(&sdf[2][k], b * cx);
      simd::store(&sdf[3][k], b * cy);
      simd::store(&sdf[4][k], a);
      simd::store(&sdf[5][k], b);
    }
  }
  if (s.inner_radius > 0)
    for (int j = 0; j < 6; ++j) multiply(sdf[j], inner, n8, sd_in[j]);
  const Eigen::Matrix<double, 6, 6> H = gram(sdf, sdf, n8);
  Eigen::Matrix<double, 6, 6> Hin = Eigen::Matrix<double, 6, 6>::Zero();  // over the inner pixels
  if (s.inner_radius > 0) Hin = gram(sd_in, sdf, n8);
  // The part of H (and Hin) the template's own noise puts in it through its gradients, per unit of
  // gradient noise variance (errors in variables, below): sd = g (x) u with u = (qx, qy, 1), so
  // E[sd sd^T] = cov(g)(c_i, c_j) u_i u_j: the sums of u u^T suffice, over the whole window (all)
  // and its inner pixels (in), in moment_matrix's order: qx^2, qx qy, qy^2, qx, qy, 1.
  const auto moments = [&](const float* mask) {
    alignas(32) float mx[kMaxN8], my[kMaxN8];
    multiply(qx, mask, n8, mx);
    multiply(qy, mask, n8, my);
    const float* bx[2] = {qy, mask};
    const float* by[1] = {mask};
    double rx[3], ry[2], rm[1];
    // (qx m) qx, (qx m) qy, (qx m) m = qx m for a 0/1 mask; likewise for qy and m itself.
    lk_dots::dot_many(mx, 0.f, bx, 2, n8, rx);
    lk_dots::dot_many(my, 0.f, by, 1, n8, ry);
    lk_dots::dot_many(mask, 0.f, nullptr, 0, n8, rm);
    std::array<double, 6> m{};
    m[0] = rx[0];  // sum (qx m)^2 = sum qx^2 m
    m[1] = rx[1];
    m[3] = rx[2];
    m[2] = ry[0];
    m[4] = ry[1];
    m[5] = rm[0];
    return m;
  };
  const std::array<double, 6> all = moments(ones);
  const std::array<double, 6> in = s.inner_radius > 0 ? moments(inner) : std::array<double, 6>{};
  const Eigen::Matrix2d gq = to_q.transpose() * to_q;  // cov(g) per unit of gradient noise variance
  const auto noise_part = [&gq](const Eigen::Matrix3d& u) {
    static constexpr int kG[6] = {0, 0, 1, 1, 0, 1}, kU[6] = {0, 1, 0, 1, 2, 2};
    Eigen::Matrix<double, 6, 6> e;
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) e(i, j) = gq(kG[i], kG[j]) * u(kU[i], kU[j]);
    return e;
  };
  const Eigen::Matrix<double, 6, 6> En = noise_part(moment_matrix(all)),
                                    En_in = noise_part(moment_matrix(in));
  SpdFactor<6> h_factor;
  if (!h_factor.factor(H)) return out;
  // The template's side of the sums below, once: sum_k sd_k, sum_k sd_k t_k, sum_k t_k (0 up to the
  // float rounding of t) and sum_k t_k^2 (1 up to it).
  Eigen::Matrix<double, 6, 1> sd_sum, sd_t;
  double t_sum = 0, tt = 0;
  {
    const float* rows[7] = {sdf[0], sdf[1], sdf[2], sdf[3], sdf[4], sdf[5], t};
    double r[8];
    lk_dots::dot_many(ones, 0.f, rows, 7, n8, r);
    sd_sum = Eigen::Map<const Eigen::Matrix<double, 6, 1>>(r + 1);
    t_sum = r[7];
    lk_dots::dot_many(t, 0.f, rows, 6, n8, r);
    tt = r[0];
    sd_t = Eigen::Map<const Eigen::Matrix<double, 6, 1>>(r + 1);
  }
  // The warp as a 3x3 matrix, template coordinates (relative to (u, v)) -> target raw pixels.
  Eigen::Matrix3d M = Eigen::Matrix3d::Identity();
  if (start_linear)
    M.topLeftCorner<2, 2>() = *start_linear;
  else if (!shape)
    M.topLeftCorner<2, 2>() = A0;
  M.topRightCorner<2, 1>() = start;
  alignas(32) float wi[kMaxN8];
  // The warped window wi, normalised to zero mean and unit norm (w = sc (wi - m)), enters only
  // through e_k = w_k - t_k: b = sum_k sd_k e_k = sc (sum_k sd_k wi_k - m sd_sum) - sd_t and
  // SSR = sum_k e_k^2 = sc^2 var - 2 sc (sum_k wi_k t_k - m t_sum) + tt, so one pass of nine dot
  // products over the samples replaces normalising them and summing the residual (three passes).
  // Every one of these is unchanged when the samples are taken about a centre c (wi - c, m - c):
  // the float sums of lk_dots then do not cancel (var = sum wi^2 - m sum wi about 0 would lose
  // ~(mean / contrast)^2 ~ 1e4 of float's 6e-8). c: the last sample's mean (the template's first).
  Eigen::Matrix<double, 6, 1> grad;         // b above
  double ssr = 0, mean_c = 0, scale_w = 0;  // the last sample's SSR, centred mean and 1 / norm
  float centre = static_cast<float>(mean), used_centre = centre;
  auto sample = [&]() {
    const Eigen::Vector2d c = M.topRightCorner<2, 1>();
    const int ci = round_half_away(c.x()), ri = round_half_away(c.y());
    if (ci < 0 || ri < 0 || ci >= dst.width || ri >= dst.height || !dst_usable[ri * dst.width + ci])
      return false;
    lk_sample::Warp w;
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < 3; ++c) w.m[3 * r + c] = static_cast<float>(M(r, c));
    if (!lk_sample::sample_window(dst, w, qx, qy, n, wi)) return false;
    std::fill(wi + n, wi + n8, centre);  // the padding: wi - centre = 0
    used_centre = centre;
    const float* rows[8] = {ones, t, sdf[0], sdf[1], sdf[2], sdf[3], sdf[4], sdf[5]};
    double r[9];
    lk_dots::dot_many(wi, centre, rows, 8, n8, r);
    const double s2 = r[0], s1 = r[1], st = r[2];
    const Eigen::Map<const Eigen::Matrix<double, 6, 1>> p(r + 3);
    const double m = s1 / n, var = s2 - s1 * m;
    if (!(var > 0)) return false;
    const double sc = 1.0 / std::sqrt(var);
    grad = sc * (p - m * sd_sum) - sd_t;
    ssr = std::max(0.0, 1.0 - 2.0 * sc * (st - m * t_sum) + tt);
    mean_c = m;
    scale_w = sc;
    centre += static_cast<float>(m);
    return true;
  };
  // One Gauss-Newton step from the last sample (inverse composition: W <- W o W(dp)^-1); returns
  // how far it moved the centre.
  const auto step = [&]() {
    const Eigen::Matrix<double, 6, 1> dp = h_factor.solve(grad);
    Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
    D(0, 0) += dp(0);
    D(0, 1) = dp(1);
    D(1, 0) = dp(2);
    D(1, 1) += dp(3);
    D(0, 2) = dp(4);
    D(1, 2) = dp(5);
    const Eigen::Vector2d before = M.topRightCorner<2, 1>();
    M = M * D.inverse();
    return (M.topRightCorner<2, 1>() - before).norm();
  };
  for (int it = 0; it < s.max_iterations; ++it) {
    if (!sample()) return out;
    const double moved = step();
    out.iterations = it + 1;
    if ((M.topRightCorner<2, 1>() - start).norm() > s.max_travel_px) return out;
    if (moved < s.stop_step_px) {
      out.converged = true;
      break;
    }
  }
  // The residual statistics below are the final sample's. Its step is taken too (free: its sums are
  // there): the iteration converges linearly here, and what the stop test left was a bias of 0.0038 px
  // in LkAffine.NoiseFreeBias* (0.0024 px after this step: each step leaves ~0.6 of what remains). The
  // statistics move by the step's square.
  if (!out.converged || !sample()) return LkResult{};
  step();
  out.px = M.topRightCorner<2, 1>();
  out.A = M.topLeftCorner<2, 2>();
  // Both windows have unit norm: ZNCC = 1 - SSR / 2.
  out.zncc = 1.0 - 0.5 * ssr;
  // The template was scaled by 1 / sqrt(ss): residuals back in its grey levels by sqrt(ss).
  out.ssr_dn2 = ssr * ss;
  if (s.inner_radius > 0) {
    double outer = 0;
    for (int k = 0; k < n; ++k) {
      if (inner[k] != 0.f) continue;
      const double e = scale_w * (wi[k] - used_centre - mean_c) - t[k];
      outer += e * e;
    }
    out.ssr_outer_dn2 = outer * ss;
  }
  // Covariance of the template-frame translation, mapped to the target by the warp. Residual noise
  // per image pixel: s^2 = SSR / (N - tr(P C)), with correlated noise (lk_affine.hpp) the sandwich form.
  const auto& b = s.noise_kernel;
  double b2 = 0;
  for (float x : b) b2 += double(x) * x;
  const bool white = b == LkSettings{}.noise_kernel;
  out.noise_dof = n - 8;
  if (!white) {
    // The residual is (I - P) e, P the hat matrix of the fit's 8 regressors (the window's mean, its
    // gain: the template itself, and the 6 steepest-descent images), so E[SSR] = s^2 (N - tr(P C))
    // with C the noise's correlation (Seber & Lee, "Linear Regression Analysis", 2003, Thm 1.5).
    // White noise: tr(P C) = 8. Under the Bayer binomial a smooth regressor keeps more of the noise
    // (the constant one ~7x its share): on the sparse path's windows (bench_scene --bayer, the
    // simulator's blur and the measured sensor's alike) tr(P C) ~ 30 at 9 x 9, 33-36 at 13 x 13 to
    // 21 x 21, so N - 8 had the 9 x 9's residual variance 0.7x too small, and the wider window's
    // tests (sparse_wide.cpp) refused most Bayer windows for it.
    const float* const x[8] = {ones, t, sdf[0], sdf[1], sdf[2], sdf[3], sdf[4], sdf[5]};
    const Eigen::Matrix<double, 8, 8> xx = dot_gram<8>(x, n8);  // over the window's own pixels
    const Eigen::Matrix<double, 8, 8> xcx = kernel_gram<8>(b, x, side) / b2;
    const double trace = xx.partialPivLu().solve(xcx).trace();
    if (trace > 8 && trace < n) out.noise_dof = n - trace;
  }
  // The target's interpolant smooths the right eye's noise (bspline_noise_autocorrelation): at a
  // sample whose place has fractional parts (fx, fy) its variance is g = sum over lags of
  // R_fx(lx) R_fy(ly) rho(lx, ly) of the noise's own (rho: the kernel's autocorrelation; white:
  // R_fx(0) R_fy(0), 0.57 at half a pixel both ways) instead of 1. The residual holds the two eyes'
  // noise evenly, so E[SSR] loses sum_k (1 - g_k) / 2 of its degrees of freedom, while the match (a
  // sum over smooth steepest-descent images, which interpolation leaves nearly as they are) keeps
  // all of it: without this, SSR / dof read the noise 0-26 % short by the fractional shift
  // (LkAffine.ResidualVariance*, docs/scene.md "the interpolant's share"). Every third row and
  // column: the places move smoothly over the window.
  {
    double rho[2 * kNoiseLagReach + 1][2 * kNoiseLagReach + 1] = {};
    for (int i = 0; i < 9; ++i)
      for (int j = 0; j < 9; ++j) rho[j / 3 - i / 3 + 2][j % 3 - i % 3 + 2] += double(b[i]) * b[j] / b2;
    double lost = 0;
    int sampled = 0;
    for (int dr = -rad; dr <= rad; dr += 3)
      for (int dc = -rad; dc <= rad; dc += 3) {
        const int k = (dr + rad) * side + dc + rad;
        const double x = M(0, 0) * qx[k] + M(0, 1) * qy[k] + M(0, 2),
                     y = M(1, 0) * qx[k] + M(1, 1) * qy[k] + M(1, 2);
        const double fx = x - std::floor(x), fy = y - std::floor(y);
        double g;
        if (white) {
          g = bspline_noise_autocorrelation(fx, 0) * bspline_noise_autocorrelation(fy, 0);
        } else {
          double ax[kNoiseLagReach + 1], ay[kNoiseLagReach + 1];
          bspline_noise_autocorrelations(fx, ax);
          bspline_noise_autocorrelations(fy, ay);
          double rx[2 * kNoiseLagReach + 1], ry[2 * kNoiseLagReach + 1];
          for (int l = -kNoiseLagReach; l <= kNoiseLagReach; ++l) {
            rx[l + kNoiseLagReach] = ax[std::abs(l)];
            ry[l + kNoiseLagReach] = ay[std::abs(l)];
          }
          g = 0;
          for (int ly = 0; ly <= 2 * kNoiseLagReach; ++ly)
            for (int lx = 0; lx <= 2 * kNoiseLagReach; ++lx) g += ry[ly] * rx[lx] * rho[ly][lx];
        }
        lost += 1 - g;
        ++sampled;
      }
    out.noise_dof -= 0.5 * lost * n / sampled;
  }
  const double s2 = ssr / out.noise_dof;
  // Errors in variables (Fuller, "Measurement Error Models", 1987, Sec. 1.1): the steepest-descent
  // images are the noisy template's gradients, so H = sum sd sd^T holds their noise too, and the
  // fit's sensitivity is the signal's part only, Hs = H - E[noise part]. Then the shift is
  // Hs^-1 sum_k sd_k e_k and its covariance the sandwich Hs^-1 (sum sd sd^T s^2) Hs^-1, larger than
  // s^2 H^-1 by up to 1 / (1 - f)^2 where the noise is the share f of H: negligible on a sharp,
  // contrasty texture, ~1.5x where a blurred one is faint. The template's noise variance is half the
  // residual's (both eyes' noise is in it); its gradients' the kernel's share of that.
  const double grad_noise = 0.5 * s2 * gradient_noise_ratio(b);
  const Eigen::Matrix<double, 6, 6> Hs = H - grad_noise * En;
  SpdFactor<6> lds;
  // A template whose gradients are mostly its noise fixes no shift: no match.
  if (!lds.factor(Hs)) return LkResult{};
  // Only the translation's rows of Hs^-1 (symmetric: the solve against the last two unit vectors).
  const Eigen::Matrix<double, 2, 6> Pw = translation_rows(lds);
  // Pw B Pw^T with B = sum over the window grown by one pixel of (b * sd)(b * sd)^T; white: B = H.
  alignas(32) float px[kMaxN8], py[kMaxN8];
  Eigen::Matrix2d PBP;
  if (white) {
    PBP = Pw * H * Pw.transpose();
  } else {
    project(Pw, sdf, n8, px, py);
    PBP = kernel_outer(b, px, py, side);
  }
  const Eigen::Matrix2d cov_t = (white ? s2 : s2 / b2) * PBP;
  out.cov = out.A * cov_t * out.A.transpose();
  // With curvature_gain: a displacement d_k beyond the affine changes the residual by r_k = g_k . d_k
  // (g the gradient in q: sd's translation images), less what the window's normalisation (zero
  // mean, unit norm: the regressors `ones` and t) takes of it, r - mean(r) - t (t . r); the fixed
  // point moves by (SD^T Pi SD)^-1 SD^T Pi r, Pi that projection. With H^-1 and r alone the 9 x 9's
  // predicted shift was a fifth short, and 5x on a texture that is nearly a ramp over the window,
  // whose template correlates with its own steepest descent (LkAffine.CurvatureGain*). Per monomial
  // m and axis c the products g_k[c] m_k as an image against the six steepest-descent images, the
  // window and the template: six passes of nine dot products. A window whose normalisation leaves
  // its steepest descent no rank (a straight edge on the photographs' board) has no gain to give:
  // its match stands, without one.
  SpdFactor<6> projected;
  out.has_curvature_gain = s.curvature_gain && projected.factor(Hs - sd_sum * sd_sum.transpose() / n -
                                                                sd_t * sd_t.transpose() / tt);
  if (out.has_curvature_gain) {
    const Eigen::Matrix<double, 2, 6> Pp = translation_rows(projected);
    alignas(32) float gm[kMaxN8];
    const auto& mono = monomials(rad);
    const float* const rows[8] = {sdf[0], sdf[1], sdf[2], sdf[3], sdf[4], sdf[5], ones, t};
    for (int m = 0; m < 3; ++m)
      for (int c = 0; c < 2; ++c) {
        multiply(sdf[4 + c], mono[m], n8, gm);  // the gradient in q (sd's translation images) m
        double r[9];
        lk_dots::dot_many(gm, 0.f, rows, 8, n8, r);
        const Eigen::Matrix<double, 6, 1> sum =
            Eigen::Map<const Eigen::Matrix<double, 6, 1>>(r + 1) - sd_sum * (r[7] / n) - sd_t * (r[8] / tt);
        out.curvature_gain[static_cast<std::size_t>(m)].col(c) = out.A * (Pp * sum);
      }
  }
  if (s.inner_radius > 0) {
    // Linearised, each fit's translation is a weighted sum of the residuals: H^-1 sum_k sd_k e_k, the
    // inner fit's over its own pixels. Their difference is sum_k g_k e_k, whose covariance is the
    // same sandwich over g (exact for correlated noise, where the wide fit is not the efficient one
    // and Hausman's Sigma_inner - Sigma_wide does not hold).
    SpdFactor<6> lin;
    if (!lin.factor(Hin - grad_noise * En_in)) return LkResult{};
    const Eigen::Matrix<double, 2, 6> Pin = translation_rows(lin);
    Eigen::Matrix2d G;
    if (white) {
      // sum_k g_k g_k^T with g_k = (Pin [k inner] - Pw) sd_k, from the sums H and Hin.
      const Eigen::Matrix2d cross = Pw * Hin * Pin.transpose();
      G = Pw * H * Pw.transpose() - cross - cross.transpose() + Pin * Hin * Pin.transpose();
    } else {
      // g_k = (Pin [k inner] - Pw) sd_k: -Pw over the window, Pin over sd_in (sd on the inner pixels).
      project(-Pw, sdf, n8, px, py);
      project(Pin, sd_in, n8, px, py, true);
      G = kernel_outer(b, px, py, side);
    }
    out.diff_cov_unit = out.A * (white ? G : Eigen::Matrix2d(G / b2)) * out.A.transpose();
    out.template_ss_dn2 = ss;
  }
  return out;
}

}  // namespace naneye::recon::scene
