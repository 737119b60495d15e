// Inverse-compositional affine Lucas-Kanade (lk_affine.hpp).
#include "naneye/recon/scene/lk_affine.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>

#include "lk_sample.hpp"
#include "round.hpp"
#include "spd_factor.hpp"

namespace naneye::recon::scene {
namespace {

// sum_p (b * v)_p (b * v)_p^T over the window grown by one pixel (the kernel's reach), v zero outside
// the side x side window: the noise of a weighted sum of v under the pair's 3 x 3 noise kernel b.
template <int D, std::size_t N>
Eigen::Matrix<double, D, D> kernel_outer(const std::array<float, 9>& b,
                                         const std::array<Eigen::Matrix<double, D, 1>, N>& v, int side) {
  Eigen::Matrix<double, D, D> out = Eigen::Matrix<double, D, D>::Zero();
  for (int r = -1; r <= side; ++r)
    for (int c = -1; c <= side; ++c) {
      Eigen::Matrix<double, D, 1> f = Eigen::Matrix<double, D, 1>::Zero();
      for (int i = -1; i <= 1; ++i)
        for (int j = -1; j <= 1; ++j) {
          const int rr = r + i, cc = c + j;
          if (rr < 0 || cc < 0 || rr >= side || cc >= side) continue;
          f += double(b[static_cast<std::size_t>((i + 1) * 3 + j + 1)]) *
               v[static_cast<std::size_t>(rr * side + cc)];
        }
      out.noalias() += f * f.transpose();
    }
  return out;
}
constexpr int kMaxN = 15 * 15;

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

void add_moments(std::array<double, 6>& m, double x, double y) {
  m[0] += x * x;
  m[1] += x * y;
  m[2] += y * y;
  m[3] += x;
  m[4] += y;
  m[5] += 1;
}

// sum u u^T, u = (x, y, 1), from add_moments' sums.
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
  if (n > kMaxN || n <= 8) return out;
  // Template, normalised to zero mean and unit norm (and its gradients by the same scale).
  std::array<float, kMaxN> t{};
  std::array<Eigen::Matrix<double, 6, 1>, kMaxN> sd;
  double mean = 0;
  for (int dr = -rad, k = 0; dr <= rad; ++dr)
    for (int dc = -rad; dc <= rad; ++dc, ++k) mean += t[k] = src.at(u + dc, v + dr);
  mean /= n;
  double ss = 0;
  for (int k = 0; k < n; ++k) ss += (t[k] - mean) * (t[k] - mean);
  if (!(ss > 0)) return out;
  const double scale = 1.0 / std::sqrt(ss);
  // The warp's domain: the template pixels themselves, or their predicted places in the target
  // (`shape`), where the template's gradient is d T / d q = d T / d x * A0^-1 (A0 varies little over
  // the window; a gradient slightly off only slows convergence, the fixed point stays).
  std::array<Eigen::Vector2d, kMaxN> q;
  std::array<float, kMaxN> qx{}, qy{};  // q as the sampling kernel reads it
  const Eigen::Matrix2d to_q = shape ? Eigen::Matrix2d(A0.inverse()) : Eigen::Matrix2d::Identity();
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 6> Hin = H;  // over the inner pixels (LkSettings::inner_radius)
  // The part of H (and Hin) the template's own noise puts in it through its gradients, per unit of
  // gradient noise variance (errors in variables, below): sd = (gx u0, gx u1, gy u0, gy u1, gx u2,
  // gy u2) with u = (qx, qy, 1), so E[sd sd^T] = cov(g)(c_i, c_j) u_i u_j: the sums of u u^T suffice.
  // Sums of qx^2, qx qy, qy^2, qx, qy, 1 over the ring (ring) and the inner pixels (in).
  std::array<double, 6> ring{}, in{};
  for (int dr = -rad, k = 0; dr <= rad; ++dr)
    for (int dc = -rad; dc <= rad; ++dc, ++k) {
      t[k] = static_cast<float>((t[k] - mean) * scale);
      q[k] = shape ? shape[k] : Eigen::Vector2d(dc, dr);
      qx[k] = static_cast<float>(q[k].x());
      qy[k] = static_cast<float>(q[k].y());
      const std::size_t p = static_cast<std::size_t>(v + dr) * src.width + u + dc;
      const Eigen::RowVector2d g = Eigen::RowVector2d(tgx[p] * scale, tgy[p] * scale) * to_q;
      // d W / d p at q for W(q) = (I + [p0 p1; p2 p3]) q + (p4, p5).
      sd[k] << g.x() * q[k].x(), g.x() * q[k].y(), g.y() * q[k].x(), g.y() * q[k].y(), g.x(), g.y();
      const double ux = q[k].x(), uy = q[k].y();
      // With inner_radius, H = Hin + the ring's sum (one outer product per pixel either way).
      if (s.inner_radius > 0 && std::max(std::abs(dr), std::abs(dc)) <= s.inner_radius) {
        Hin.noalias() += sd[k] * sd[k].transpose();
        add_moments(in, ux, uy);
      } else {
        H.noalias() += sd[k] * sd[k].transpose();
        add_moments(ring, ux, uy);
      }
    }
  H += Hin;
  for (std::size_t i = 0; i < 6; ++i) ring[i] += in[i];  // the whole window
  const Eigen::Matrix2d gq = to_q.transpose() * to_q;    // cov(g) per unit of gradient noise variance
  const auto noise_part = [&gq](const Eigen::Matrix3d& u) {
    static constexpr int kG[6] = {0, 0, 1, 1, 0, 1}, kU[6] = {0, 1, 0, 1, 2, 2};
    Eigen::Matrix<double, 6, 6> e;
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) e(i, j) = gq(kG[i], kG[j]) * u(kU[i], kU[j]);
    return e;
  };
  const Eigen::Matrix<double, 6, 6> En = noise_part(moment_matrix(ring)),
                                    En_in = noise_part(moment_matrix(in));
  SpdFactor<6> h_factor;
  if (!h_factor.factor(H)) return out;
  // The template's side of the sums below, once: sum_k sd_k, sum_k sd_k t_k, sum_k t_k (0 up to the
  // float rounding of t) and sum_k t_k^2 (1 up to it).
  Eigen::Matrix<double, 6, 1> sd_sum = Eigen::Matrix<double, 6, 1>::Zero(), sd_t = sd_sum;
  double t_sum = 0, tt = 0;
  for (int k = 0; k < n; ++k) {
    sd_sum += sd[k];
    sd_t.noalias() += sd[k] * double(t[k]);
    t_sum += t[k];
    tt += double(t[k]) * t[k];
  }
  // The warp as a 3x3 matrix, template coordinates (relative to (u, v)) -> target raw pixels.
  Eigen::Matrix3d M = Eigen::Matrix3d::Identity();
  if (start_linear)
    M.topLeftCorner<2, 2>() = *start_linear;
  else if (!shape)
    M.topLeftCorner<2, 2>() = A0;
  M.topRightCorner<2, 1>() = start;
  std::array<float, kMaxN> wi{};
  // The warped window wi, normalised to zero mean and unit norm (w = sc (wi - m)), enters only
  // through e_k = w_k - t_k: b = sum_k sd_k e_k = sc (sum_k sd_k wi_k - m sd_sum) - sd_t and
  // SSR = sum_k e_k^2 = sc^2 var - 2 sc (sum_k wi_k t_k - m t_sum) + tt, so one pass of nine dot
  // products over the raw samples replaces normalising them and summing the residual (three passes).
  // Double sums of float samples: var = sum wi^2 - m sum wi cancels ~(mean / contrast)^2 ~ 1e4 of
  // 1e-16, far below the noise.
  Eigen::Matrix<double, 6, 1> grad;         // b above
  double ssr = 0, mean_w = 0, scale_w = 0;  // the last sample's SSR, window mean and 1 / norm
  auto sample = [&]() {
    const Eigen::Vector2d c = M.topRightCorner<2, 1>();
    const int ci = round_half_away(c.x()), ri = round_half_away(c.y());
    if (ci < 0 || ri < 0 || ci >= dst.width || ri >= dst.height || !dst_usable[ri * dst.width + ci])
      return false;
    lk_sample::Warp w;
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < 3; ++c) w.m[3 * r + c] = static_cast<float>(M(r, c));
    if (!lk_sample::sample_window(dst, w, qx.data(), qy.data(), n, wi.data())) return false;
    double s1 = 0, s2 = 0, st = 0;
    Eigen::Matrix<double, 6, 1> p = Eigen::Matrix<double, 6, 1>::Zero();
    for (int k = 0; k < n; ++k) {
      const double x = wi[k];
      s1 += x;
      s2 += x * x;
      st += x * t[k];
      p.noalias() += sd[k] * x;
    }
    const double m = s1 / n, var = s2 - s1 * m;
    if (!(var > 0)) return false;
    const double sc = 1.0 / std::sqrt(var);
    grad = sc * (p - m * sd_sum) - sd_t;
    ssr = std::max(0.0, 1.0 - 2.0 * sc * (st - m * t_sum) + tt);
    mean_w = m;
    scale_w = sc;
    return true;
  };
  for (int it = 0; it < s.max_iterations; ++it) {
    if (!sample()) return out;
    const Eigen::Matrix<double, 6, 1> dp = h_factor.solve(grad);
    Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
    D(0, 0) += dp(0);
    D(0, 1) = dp(1);
    D(1, 0) = dp(2);
    D(1, 1) += dp(3);
    D(0, 2) = dp(4);
    D(1, 2) = dp(5);
    const Eigen::Vector2d before = M.topRightCorner<2, 1>();
    M = M * D.inverse();  // inverse composition: W <- W o W(dp)^-1
    out.iterations = it + 1;
    const Eigen::Vector2d now = M.topRightCorner<2, 1>();
    if ((now - start).norm() > s.max_travel_px) return out;
    if ((now - before).norm() < s.stop_step_px) {
      out.converged = true;
      break;
    }
  }
  if (!out.converged || !sample()) return LkResult{};
  out.px = M.topRightCorner<2, 1>();
  out.A = M.topLeftCorner<2, 2>();
  // Both windows have unit norm: ZNCC = 1 - SSR / 2.
  out.zncc = 1.0 - 0.5 * ssr;
  // The template was scaled by 1 / sqrt(ss): residuals back in its grey levels by sqrt(ss).
  out.ssr_dn2 = ssr * ss;
  if (s.inner_radius > 0) {
    double outer = 0;
    for (int dr = -rad, k = 0; dr <= rad; ++dr)
      for (int dc = -rad; dc <= rad; ++dc, ++k) {
        if (std::max(std::abs(dr), std::abs(dc)) <= s.inner_radius) continue;
        const double e = scale_w * (wi[k] - mean_w) - t[k];
        outer += e * e;
      }
    out.ssr_outer_dn2 = outer * ss;
  }
  // Covariance of the template-frame translation, mapped to the target by the warp. Residual noise
  // per image pixel: s^2 = SSR / (N - 8); with correlated noise (lk_affine.hpp) the sandwich form.
  const double s2 = ssr / (n - 8);
  const auto& b = s.noise_kernel;
  double b2 = 0;
  for (float x : b) b2 += double(x) * x;
  const bool white = b == LkSettings{}.noise_kernel;
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
  // (b * SD) over the window grown by one pixel; white: B = H.
  const Eigen::Matrix<double, 6, 6> B = white ? H : kernel_outer(b, sd, side);
  const Eigen::Matrix2d cov_t = (white ? s2 : s2 / b2) * Pw * B * Pw.transpose();
  out.cov = out.A * cov_t * out.A.transpose();
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
      std::array<Eigen::Vector2d, kMaxN> g;
      for (int dr = -rad, k = 0; dr <= rad; ++dr)
        for (int dc = -rad; dc <= rad; ++dc, ++k) {
          g[k] = -Pw * sd[k];
          if (std::max(std::abs(dr), std::abs(dc)) <= s.inner_radius) g[k] += Pin * sd[k];
        }
      G = kernel_outer(b, g, side);
    }
    out.diff_cov_unit = out.A * (white ? G : Eigen::Matrix2d(G / b2)) * out.A.transpose();
    out.template_ss_dn2 = ss;
  }
  return out;
}

}  // namespace naneye::recon::scene
