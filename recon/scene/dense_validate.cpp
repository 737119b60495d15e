// The rectified matcher's validity decisions (dense_match.hpp): every sub-pixel match against the
// residual, sigma, shift, left-right and occlusion tests, with the residual's expected level per
// window class; the integer stage is in dense_match.cpp, the sub-pixel step in dense_subpixel.cpp.
#include <algorithm>
#include <cmath>
#include <limits>

#include "dense_simd.hpp"
#include "naneye/recon/corners/noise.hpp"
#include "naneye/recon/scene/dense_match.hpp"
#include "round.hpp"
#include "select.hpp"
#include "sgm.hpp"

namespace naneye::recon::scene {
void RectifiedMatcher::level_medians(float min_n) {
  const dense_simd::Spans sp{span_lo_.data(), span_hi_.data(), w_, h_};
  // Every window validate() may test (one log per window, not one per use) and those whose residual
  // enters the medians.
  auto candidate = [&](std::size_t i) { return std::isfinite(d_[i]) && n_[i] >= min_n; };
  auto usable = [&](std::size_t i) { return candidate(i) && s2_[i] > 0; };
  float lo[2] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::max()};
  float hi[2] = {std::numeric_limits<float>::lowest(), std::numeric_limits<float>::lowest()};
  sp.each([&](std::size_t i) {
    if (!candidate(i)) return;
    float* f = &features_[2 * i];
    window_features(i, f);
    if (!(s2_[i] > 0)) return;
    for (int k = 0; k < 2; ++k) {
      lo[k] = std::min(lo[k], f[k]);
      hi[k] = std::max(hi[k], f[k]);
    }
  });
  for (int k = 0; k < 2; ++k) {
    bin_lo_[k] = lo[k];
    bin_step_[k] = hi[k] > lo[k] ? (hi[k] - lo[k]) / kBinsPerAxis : 1.f;
  }
  std::array<int, kBins + 1> start{};
  sp.each([&](std::size_t i) {
    if (!candidate(i)) return;
    bin_[i] = static_cast<std::uint8_t>(bin_of(&features_[2 * i]));
    if (s2_[i] > 0) ++start[static_cast<std::size_t>(bin_[i]) + 1];
  });
  for (int b = 0; b < kBins; ++b) start[b + 1] += start[b];
  std::array<int, kBins> fill{};
  sp.each([&](std::size_t i) {
    if (usable(i)) {
      const int b = bin_[i];
      scratch_[static_cast<std::size_t>(start[b] + fill[b]++)] = s2_[i];
    }
  });
  for (int b = 0; b < kBins; ++b) {
    const int cnt = start[b + 1] - start[b];
    bin_median_[b] = -1;
    bin_nu_[b] = 0;
    if (cnt < kMinPerBin) continue;
    // The bucket selection (select.hpp) rather than std::nth_element: the same values (the lower
    // quantile's rank lies below the median's, so it is the whole bin's as it was the lower half's),
    // and std::nth_element over the 64 bins was ~2 % of the dense path's time in perf.
    float* first = scratch_.data() + start[b];
    const auto ucnt = static_cast<std::size_t>(cnt);
    float med, low;
    kth_smallest_pair(first, ucnt, ucnt / 2, static_cast<std::size_t>(kResidualLowerQuantile * cnt),
                      select_hist_, med, low);
    bin_median_[b] = med;
    bin_nu_[b] = static_cast<float>(effective_dof(low, med));
  }
  const int all = start[kBins];
  residual_sigma_ = 0;
  global_median_ = std::numeric_limits<double>::infinity();
  global_nu_ = 0;
  if (all > 0) {
    const auto n = static_cast<std::size_t>(all);
    float med, low;
    kth_smallest_pair(scratch_.data(), n, n / 2, static_cast<std::size_t>(kResidualLowerQuantile * all),
                      select_hist_, med, low);
    global_median_ = med;
    global_nu_ = effective_dof(low, global_median_);
    residual_sigma_ = std::sqrt(global_median_);
  }
}

void RectifiedMatcher::window_features(std::size_t i, float f[2]) const {
  const std::size_t n = static_cast<std::size_t>(w_) * h_;
  const float N = n_[i], sl = sums_[2 * n + i];
  // The window's mean level (shot noise grows with it) and the log of its left contrast (the
  // resampling's misfit grows with the texture's amplitude).
  f[0] = sl / N;
  f[1] = std::log(std::max(1e-6f, sums_[9 * n + i] / N - f[0] * f[0]));
}

int RectifiedMatcher::bin_of(const float f[2]) const {
  int b[2];
  for (int k = 0; k < 2; ++k)
    b[k] = std::clamp(static_cast<int>((f[k] - bin_lo_[k]) / bin_step_[k]), 0, kBinsPerAxis - 1);
  return b[0] * kBinsPerAxis + b[1];
}

double RectifiedMatcher::expected_residual(std::size_t i) const {
  const float m = bin_median_[bin_[i]];  // level_medians() binned every window validate() tests
  return m > 0 ? m : global_median_;
}

double RectifiedMatcher::expected_dof(std::size_t i) const {
  return bin_median_[bin_[i]] > 0 ? bin_nu_[bin_[i]] : global_nu_;
}

void RectifiedMatcher::validate(const cv::Mat& valid_left) {
  const int side = 2 * r_ + 1;
  // The sigma this pixel would have one radius smaller, for the same texture: the sum of squared
  // gradients grows with the window's area, so sigma ~ 1 / (2 r + 1) (validate counts the candidates
  // that would cross the bound there, choose_radius predicts from them).
  const double shrunk = static_cast<double>(side) / std::max(1, side - 2);
  int marginal = 0;
  const float min_n = static_cast<float>(s_.min_window_share * side * side);
  // The residual variance a window like this one should have: the median over the windows of
  // similar mean level (shot noise grows with the level, and the light's 1/d^2 spreads levels over
  // the frame) and similar contrast (the resampling's misfit grows with the texture's amplitude).
  // That is the pair's noise and misfit as the fit sees them, interpolation and demosaicing
  // included; a wrong match or an occlusion stands out against it.
  level_medians(min_n);
  const double zq = upper_normal_quantile(s_.residual_p);
  MatchCounts c;
  const int matchable_from = sgm_->first_column();
  for (int y = 0; y < h_; ++y) {
    const std::uint8_t* vl = valid_left.ptr<std::uint8_t>(y);
    const float* sg = integer_.ptr<float>(y);
    float* od = disp_.ptr<float>(y);
    float* os = sigma_.ptr<float>(y);
    for (int x = 0; x < w_; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w_ + x;
      od[x] = kNoMatch;
      os[x] = kNoMatch;
      if (!vl[x]) continue;
      ++c.candidates;
      const float d = d_[i];
      if (!std::isfinite(sg[x])) {
        // The SGM matches every column of the spans from min + number of disparities on (no
        // uniqueness or speckle filter): a pixel it left without one there failed its left-right
        // check, or (+infinity) its best lay on an edge of a narrowed band.
        ++(std::isinf(sg[x]) ? c.band_edge : x >= matchable_from ? c.left_right : c.no_integer);
        continue;
      }
      if (!std::isfinite(d) || n_[i] < min_n || !(a_[i] > 0)) {
        ++c.window;
        continue;
      }
      if (std::abs(d - sg[x]) > s_.max_shift_px) {
        ++c.shift;
        continue;
      }
      const double zc = eiv_zc(i);
      // The window's residual variance is a 49-121 pixel estimate (~20-30 % spread): one low by
      // chance would claim less noise than the pair has for such a window. Never below the median of
      // its kind; its own excess where it has one (the chi-square test below bounds that).
      // docs/scene.md, "A floor under the window's noise".
      // (No median at all, when no window had a residual: the window's own.)
      const double kind = expected_residual(i);
      const double s2 = std::isfinite(kind) ? std::max(static_cast<double>(s2_[i]), kind) : s2_[i];
      // G is the left's gradient, a times the right's: c is the step itself, its sigma no 1 / a.
      const double sigma = std::sqrt(std::max(0.f, kappa_px_[i]) * s2 * zc);
      if (!(sigma <= s_.max_sigma_px)) {
        ++c.texture;
        continue;
      }
      marginal += sigma * shrunk > s_.max_sigma_px;
      if (std::abs(smooth_step_[i]) > std::max(sigma, 1e-3)) {
        ++c.converged;
        continue;
      }
      // Chi-square upper quantile over the window's effective degrees of freedom.
      const double nu = std::max(
          1.0, std::min((n_[i] - 3.0) / std::max(1.0, static_cast<double>(kappa_px_[i])), expected_dof(i)));
      if (s2_[i] > expected_residual(i) * chi2_upper_ratio(nu, zq)) {
        ++c.residual;
        continue;
      }
      od[x] = d;
      os[x] = static_cast<float>(sigma);
    }
  }
  // Occlusion: a nearer surface (larger disparity) landing on the same right pixel hides this one.
  for (int y = 0; y < h_; ++y) {
    float* od = disp_.ptr<float>(y);
    float* best = line_.data();
    std::fill(best, best + w_, -1.f);
    for (int x = 0; x < w_; ++x) {
      if (!std::isfinite(od[x])) continue;
      const int xr = round_half_away(static_cast<float>(x) - od[x]);
      if (xr >= 0 && xr < w_) best[xr] = std::max(best[xr], od[x]);
    }
    for (int x = 0; x < w_; ++x) {
      if (!std::isfinite(od[x])) continue;
      const int xr = round_half_away(static_cast<float>(x) - od[x]);
      if (xr < 0 || xr >= w_ || best[xr] > od[x] + s_.occlusion_px) {
        ++c.occluded;
        od[x] = kNoMatch;
        sigma_.ptr<float>(y)[x] = kNoMatch;
      } else {
        ++c.valid;
      }
    }
  }
  c.radius = r_;
  counts_ = c;
  marginal_ = marginal;
}

// (A^-1)_cc of the last fit, with the regressors' own noise taken out (errors in variables; Fuller,
// "Measurement Error Models", 1987, Sec. 1.1): W is the noisy right image, G the noisy left's
// gradient, so the centred sums A = [Sww -Swg; -Swg Sgg] hold N times their noise variances, and
// the fit's sensitivity is As = A - N diag(vw, vg). The estimate's variance per unit residual
// variance is the sandwich (As^-1 M As^-1)_cc: larger than (A^-1)_cc where the texture is faint
// against the noise (a blurred image), nearly the same on a sharp one. M is A but for one term: G's
// noise is the left pixels' noise filtered by D (bspline_knot_derivative_tap), and the residual
// holds the same left noise at the neighbouring pixels, so sum G r carries the products of the two,
// whose expectation over a window is -N vl^2 sum_m e(m) e(-m) (e = D * rho; for white noise
// -N vl^2 sum D_k^2: D is odd); per unit residual variance, M_gg = Sgg - N grad_cross_ratio_ vl^2 / s^2.
// (Its expectation at the same pixel, sum_k D_k rho(k), is 0: D odd, rho even, so G's noise biases
// no step. The right image's gradient, used until 2026-12-06, shares the interpolated right noise
// with W at every pixel, and that bias moved each match by up to 0.7 sigma at low signal to noise,
// varying with the disparity's fraction: docs/scene.md, "The gradient from the left".) The left
// image's noise variance vl comes from the residual's, s^2 = vl (1 + a^2) (the eyes alike); vw = vl,
// vg = grad_noise_ratio_ vl. A window whose gradient is mostly noise (As not positive) gives infinity:
// no sigma to stand behind.
double RectifiedMatcher::eiv_zc(std::size_t i) const {
  const double N = n_[i], a = a_[i];
  const double v = s2_[i] / (1.0 + a * a);
  const double p = sww_[i], q = swg_[i], r = sgg_[i];
  const double ps = p - N * v, rs = r - N * grad_noise_ratio_ * v;
  const double dets = ps * rs - q * q;
  if (!(ps > 0 && rs > 0 && dets > 0)) return std::numeric_limits<double>::infinity();
  // As^-1 = [rs q; q ps] / dets (As = [ps -q; -q rs]); its c row: (q, ps) / dets.
  const double u = q / dets, w = ps / dets;
  const double r_mid = r - N * grad_cross_ratio_ * v / (1.0 + a * a);
  const double zc = u * u * p - 2 * u * w * q + w * w * r_mid;
  return zc > 0 ? zc : std::numeric_limits<double>::infinity();
}

}  // namespace naneye::recon::scene
