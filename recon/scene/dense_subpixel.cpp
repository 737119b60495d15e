// The rectified matcher's sub-pixel step and its noise correlation (dense_match.hpp).
//
// Model per pixel p, over its window: L(x) = a R(x - d_x) + b, each window pixel x at its own current
// disparity d_x, linearised in a common step: a R(x - d_x - delta) ~ a W_x - G_x delta (W the right
// image sampled there; G the left image's x derivative, which is a R'(x - d_x) where the model holds:
// the gradient of the template, as in inverse-compositional LK, Baker & Matthews 2004). The model is
// linear in (a, b, c = delta): regressors W, 1, -G. Eliminating b by centring (window means), the
// normal equations are 2 x 2:
//   [Sww  -Swg] [a]   [ Swl]
//   [-Swg  Sgg] [c] = [-Sgl],   S.. the centred window sums.
// Every sum is a box filter of a per-pixel product, so the cost per pixel does not depend on the
// window. Var(c) = s^2 (A^-1)_cc with s^2 = SSR / (N - 3), corrected for the regressors' noise
// (dense_match.cpp, eiv_zc). Why the left's gradient and not the right's (until 2026-12-06): the right's,
// sampled with W from the same spline, shares W's interpolated noise, E[n_W n_G] = v_r sum_k
// eta_k(t) eta_k'(t) at the sample's fraction t, and the normal equations then move the step by
// N E[n_W n_G] / Sgg, a bias of up to 0.7 sigma at low signal to noise, zero only at t = 0 and 1/2
// (bench_dense_snr, docs/scene.md "The gradient from the left"). The left's gradient is taken at its
// pixels by an odd filter, whose noise is uncorrelated with the same pixel's (rho is even).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "../corners/simd.hpp"
#include "dense_simd.hpp"
#include "naneye/recon/scene/bspline.hpp"
#include "naneye/recon/scene/dense_match.hpp"
#include "select.hpp"

namespace naneye::recon::scene {
namespace {
using dense_simd::Spans;
constexpr int kChannels = 10;  // m, W, L, G, WW, GG, WG, WL, GL, LL
// px; the residual autocorrelation's reach: the window radius (noise correlated by the spline's 4 taps and
// a Bayer filter reaches 2 px; the resampling's misfit follows the texture, further).
constexpr int kLag = 3;

// f.template operator()<T>(i) on the spans' pixels: T four floats (an SSE2 vector: the x86-64
// baseline) where four pixels of the row remain, else float. For element-wise steps written once for
// both, so the lanes and the tails compute the same expressions: the plain loop's bits.
using F4 = simd::V4;
using simd::load;
using simd::store;
template <class F>
void each4(const Spans& sp, F&& f) {
  for (int y = 0; y < sp.h; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * sp.w;
    int x = sp.lo[y];
    for (; x + 4 <= sp.hi[y]; x += 4) f.template operator()<F4>(row + x);
    for (; x < sp.hi[y]; ++x) f.template operator()<float>(row + x);
  }
}

}  // namespace

void RectifiedMatcher::gather(const cv::Mat& left, bool last) {
  const std::size_t n = static_cast<std::size_t>(w_) * h_;
  float* ch = chan_.data();
  dense_simd::GatherRow g{};
  g.w = w_;
  g.mu = static_cast<float>(mean_);
  for (int y = 0; y < h_; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * w_;
    g.left = left.ptr<float>(y);
    g.left_grad = left_grad_.data() + row;
    g.right = right_spline_.data() + row;
    g.taps_ok = taps_ok_.data() + row;
    g.d = d_.data() + row;
    for (int k = 0; k < kChannels; ++k) g.ch[k] = ch + static_cast<std::size_t>(k) * n + row;
    g.lo = span_lo_[static_cast<std::size_t>(y)];
    g.hi = span_hi_[static_cast<std::size_t>(y)];
    dense_simd::gather_row(avx2_, g);
  }
  const Spans sp{span_lo_.data(), span_hi_.data(), w_, h_};
  // The left's own energy (LL) enters only the last fit's residual and the window features.
  for (int k = 0; k < (last ? kChannels : kChannels - 1); ++k)
    dense_simd::box_sum(avx2_, ch + k * n, sums_.data() + k * n, scratch_.data(), sp, r_);
}

void RectifiedMatcher::refine(const cv::Mat& left, const cv::Mat& valid_left) {
  const std::size_t n = static_cast<std::size_t>(w_) * h_;
  // Centre both images on the left's mean: the window sums stay small against float precision.
  double sum = 0;
  long count = 0;
  for (int y = 0; y < h_; ++y) {
    const float* l = left.ptr<float>(y);
    const std::uint8_t* vl = valid_left.ptr<std::uint8_t>(y);
    for (int x = 0; x < w_; ++x)
      if (vl[x]) {
        sum += l[x];
        ++count;
      }
  }
  mean_ = count > 0 ? sum / static_cast<double>(count) : 0.0;
  // The start 4 pixels at a time (SSE2 vectors; the tap test's mask likewise, prepare_right): as
  // plain loops both cost ~3 M instructions a pair, the tap test's four branches per pixel most of it.
  using VB4 = std::uint8_t __attribute__((vector_size(4)));
  using VF = simd::V4;
  using VI = simd::VI4;
  for (int y = 0; y < h_; ++y) {
    const float* sg = integer_.ptr<float>(y);
    const std::uint8_t* vl = valid_left.ptr<std::uint8_t>(y);
    float* d = d_.data() + static_cast<std::size_t>(y) * w_;
    int x = 0;
    for (; x + 4 <= w_; x += 4) {
      VB4 v;
      std::memcpy(&v, vl + x, sizeof v);
      const VF g = load<VF>(sg + x);
      // g - g is 0 only where g is finite (+infinity: a narrowed band's edge, sgm.hpp).
      store(d + x, (__builtin_convertvector(v, VI) != 0) & (g - g == 0) ? g : VF{} + kNoMatch);
    }
    for (; x < w_; ++x) d[x] = vl[x] && std::isfinite(sg[x]) ? sg[x] : kNoMatch;
  }
  const float* S = sums_.data();
  float* mstep = chan_.data() + 4 * n;  // free once the window sums are taken
  float* msolved = chan_.data() + 5 * n;
  const Spans sp{span_lo_.data(), span_hi_.data(), w_, h_};
  for (int it = 0; it < s_.iterations; ++it) {
    gather(left, it + 1 == s_.iterations);
    // Only the last iteration's fit is read after the loop (validate(), correlation()): a window that
    // survives it is refitted there, one that fails it has no disparity.
    const bool last = it + 1 == s_.iterations;
    if (!last) {
      // The earlier iterations keep only the step, in float on whole vectors (dense_simd::step_row):
      // the window sums are float box sums already, whose rounding (~1e-7 of the sums of squares,
      // ~2r+1 additions per pass) the centring in double does not undo; the step only moves the
      // reference, which the window mean then smooths and the last iteration's fit, in double,
      // corrects. The scalar double loop cost ~1/10 of the dense path's time.
      dense_simd::StepRow r{};
      for (int y = 0; y < h_; ++y) {
        const std::size_t row = static_cast<std::size_t>(y) * w_;
        for (int k = 0; k < 9; ++k) r.s[k] = S + static_cast<std::size_t>(k) * n + row;
        r.m = chan_.data() + row;
        r.d = d_.data() + row;
        r.out = mstep + row;
        r.solved = msolved + row;
        r.lo = span_lo_[static_cast<std::size_t>(y)];
        r.hi = span_hi_[static_cast<std::size_t>(y)];
        dense_simd::step_row(avx2_, r);
      }
    } else {
      reference_detail();
      // The last fit in double: its gain, offset, residual and variance are read after the loop.
      dense_simd::FitRow r{};
      for (int y = 0; y < h_; ++y) {
        const std::size_t row = static_cast<std::size_t>(y) * w_;
        for (int k = 0; k < 10; ++k) r.s[k] = S + static_cast<std::size_t>(k) * n + row;
        r.m = chan_.data() + row;
        r.d = d_.data() + row;
        r.n = n_.data() + row;
        r.step = mstep + row;
        r.solved = msolved + row;
        r.a = a_.data() + row;
        r.b = b_.data() + row;
        r.c = c_.data() + row;
        r.s2 = s2_.data() + row;
        r.z = z_.data() + row;
        r.sww = sww_.data() + row;
        r.swg = swg_.data() + row;
        r.sgg = sgg_.data() + row;
        r.lo = span_lo_[static_cast<std::size_t>(y)];
        r.hi = span_hi_[static_cast<std::size_t>(y)];
        dense_simd::fit_row(avx2_, r);
      }
    }
    // The window's shape is the reference field d_ (each pixel warped by its own reference
    // disparity: slanted surfaces keep their shape), its correction the window's common step. The
    // reference becomes the window mean of the corrected disparities, never a pixel's own: fed
    // back per pixel, the fixed point would be every pixel matched alone (box(G r) = 0 everywhere
    // is solved by r = 0 per pixel), the window's averaging undone and the noise amplified; and
    // the integer stage's own scatter (its pixel-locked parabola) would stay in the window shape.
    if (last) {
      // The window's estimate at the final reference, its detail replaced by the window's view of it.
      const float* q_win = window_detail();
      // Only where the detail is noise: a detail or a move beyond 3 sigma (white-noise sigma, no
      // kappa) is the surface's own structure, a depth edge or a fold the smooth part cannot
      // follow (ungated, Middlebury Aloe's bad-0.5 rose from 4.22 to 4.59 % with a window-sized
      // smooth part, to 5.12 % with twice that; gated, 4.31 %).
      dense_simd::UpdateRow u{};
      for (int y = 0; y < h_; ++y) {
        const std::size_t row = static_cast<std::size_t>(y) * w_;
        u.solved = msolved + row;
        u.step = mstep + row;
        u.q = chan_.data() + 7 * n + row;
        u.q_win = q_win + row;
        u.s2 = s2_.data() + row;
        u.z = z_.data() + row;
        u.d = d_.data() + row;
        u.lo = span_lo_[static_cast<std::size_t>(y)];
        u.hi = span_hi_[static_cast<std::size_t>(y)];
        dense_simd::update_row(avx2_, u);
      }
      break;
    }
    dense_simd::box_sum(avx2_, mstep, sums_.data() + 4 * n, scratch_.data(), sp, r_);
    dense_simd::box_sum(avx2_, msolved, sums_.data() + 5 * n, scratch_.data(), sp, r_);
    for (int y = 0; y < h_; ++y) {
      const std::size_t row = static_cast<std::size_t>(y) * w_;
      dense_simd::mean_row(avx2_, S + 4 * n + row, S + 5 * n + row, d_.data() + row,
                           smooth_step_.data() + row, span_lo_[static_cast<std::size_t>(y)],
                           span_hi_[static_cast<std::size_t>(y)]);
    }
  }
  correlation(valid_left);
}

// The window's estimate is d_ref(p) + delta(p), and to first order delta(p) = sum_x w_x (t_x -
// d_ref(x)) + n(p): the window's weighted view of how far the true disparities t lie from the
// reference, plus the noise whose variance the sigma states (weights w_x = -k_x G_x with
// k_x = (Swg w~_x - Sww g~_x) / det, the linear weights of c in the data; sum_x w_x = 1). So
// d_ref(p) + delta(p) = sum_x w_x t_x + n(p) + [d_ref(p) - sum_x w_x d_ref(x)]: the bracket is the
// reference's own deviation from its weighted window mean, and the reference is a window mean of
// the previous iteration's noisy estimates. Measured by Monte Carlo (bench_dense_sigma, 8 noise
// seeds): that bracket made the estimate's spread 1.09-1.38x the stated sigma. Split the reference
// into a smooth part ds (its mean over twice the window's radius) and a detail q = d_ref - ds;
// replacing q(p) by the window's own view of it, sum_x w_x q_x, leaves d = sum_x w_x t_x + [ds(p) -
// sum_x w_x ds_x] + n(p): the bracket now holds the smooth field's shape (which carries a slanted
// surface's slope across the window's weighted centre) and little noise. Twice the radius: the
// spread falls to 0.99-1.08x sigma on normal texture; at three times it falls further but the smooth
// part no longer follows the surfaces (noise-free misfit, tube 0.50 -> 0.62 sigma, height field
// 0.59 -> 0.70); at once the radius, 1.11-1.15x.
// reference_detail() (before the last fit; its sums are still needed by the fit): q into chan 7.
// window_detail() (after the fit; chan 4, 5 hold its step and flag): sum_x w_x q_x per pixel.
void RectifiedMatcher::reference_detail() {
  const std::size_t n = static_cast<std::size_t>(w_) * h_;
  float* val = chan_.data() + 7 * n;
  float* cnt = chan_.data() + 8 * n;
  float* bval = chan_.data() + 6 * n;
  float* bcnt = chan_.data() + 9 * n;
  const Spans sp{span_lo_.data(), span_hi_.data(), w_, h_};
  const float* d = d_.data();
  each4(sp, [&]<class T>(std::size_t i) {
    const T di = load<T>(d + i);
    const auto ok = di - di == 0.f;  // finite
    store(val + i, ok ? di : T{});
    store(cnt + i, ok ? T{} + 1.f : T{});
  });
  dense_simd::box_sum(avx2_, val, bval, scratch_.data(), sp, 2 * r_);
  dense_simd::box_sum(avx2_, cnt, bcnt, scratch_.data(), sp, 2 * r_);
  each4(sp, [&]<class T>(std::size_t i) {
    store(val + i, load<T>(cnt + i) > 0.f ? load<T>(d + i) - load<T>(bval + i) / load<T>(bcnt + i) : T{});
  });
}

const float* RectifiedMatcher::window_detail() {
  const std::size_t n = static_cast<std::size_t>(w_) * h_;
  const float* ch = chan_.data();
  const float* q = ch + 7 * n;
  float* wgq = chan_.data() + 6 * n;
  float* ggq = chan_.data() + 8 * n;
  float* gq = chan_.data() + 9 * n;
  const Spans sp{span_lo_.data(), span_hi_.data(), w_, h_};
  each4(sp, [&]<class T>(std::size_t i) {
    const T g = load<T>(ch + 3 * n + i), gqi = g * load<T>(q + i);
    store(gq + i, gqi);
    store(wgq + i, load<T>(ch + n + i) * gqi);
    store(ggq + i, g * gqi);
  });
  // The fit's own sums (0 N, 1 W, 3 G, 4 WW, 5 GG, 6 WG) are read here, 2 and 9 by validate()'s
  // window features: only 7 and 8 are free after the fit, and line_copy_ until correlation().
  float* S = sums_.data();
  float* sgq = line_copy_.data();
  dense_simd::box_sum(avx2_, wgq, S + 7 * n, scratch_.data(), sp, r_);
  dense_simd::box_sum(avx2_, ggq, S + 8 * n, scratch_.data(), sp, r_);
  dense_simd::box_sum(avx2_, gq, sgq, scratch_.data(), sp, r_);
  float* out = wgq;  // its sum is taken
  dense_simd::DetailRow r{};
  for (int y = 0; y < h_; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * w_;
    for (int k = 0; k < 9; ++k) r.s[k] = S + static_cast<std::size_t>(k) * n + row;
    r.sgq = sgq + row;
    r.out = out + row;
    r.lo = span_lo_[static_cast<std::size_t>(y)];
    r.hi = span_hi_[static_cast<std::size_t>(y)];
    dense_simd::detail_row(avx2_, r);
  }
  return out;
}

void RectifiedMatcher::correlation(const cv::Mat&) {
  const std::size_t n = static_cast<std::size_t>(w_) * h_;
  const float* ch = chan_.data();
  const float* S = sums_.data();
  // The last fit's residual at every pixel with data (its own window's a, b, c).
  float* e = scratch_.data();
  std::size_t m = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (ch[i] > 0 && std::isfinite(d_[i])) line_copy_[m++] = s2_[i];
  double med = 0;
  if (m > 0) {
    med = kth_smallest(line_copy_.data(), m, m / 2, select_hist_);
  }
  // Windows with a residual far above the median (occlusion, a wrong match) carry structure, not
  // noise: left out of the autocorrelation.
  const dense_simd::ResidualRow rr{ch,         ch + n,    ch + 2 * n, ch + 3 * n, d_.data(),
                                   s2_.data(), a_.data(), b_.data(),  c_.data(),  e};
  dense_simd::residual_row(avx2_, rr, 3 * med, 0, n);
  constexpr int kSide = 2 * kLag + 1;
  double acc[kSide][kSide];
  // Every other row and column: ~15 000 products per lag on a pair, the estimate's scatter ~0.01.
  static_assert(kLag == 3, "dense_simd::lag_products sums lags [-3, 3]^2");
  dense_simd::lag_products(avx2_, e, w_, h_, &acc[0][0]);
  const double e0 = acc[kLag][kLag] > 0 ? acc[kLag][kLag] : 1.0;
  for (int k = 0; k < kSide * kSide; ++k)
    rho_[static_cast<std::size_t>(k)] = static_cast<float>(acc[k / kSide][k % kSide] / e0);
  // The left gradient's noise (eiv_zc): the left pixels' noise through D, the spline's derivative
  // filter, correlated as the residual is along the rows (measured to lag 3, none beyond). White:
  // 1.392 and 1.392.
  const auto rho_row = [&](int l) {
    l = std::abs(l);
    return l > kLag ? 0.0 : static_cast<double>(rho_[static_cast<std::size_t>(kLag * kSide + kLag + l)]);
  };
  constexpr int kD = kKnotDerivativeReach;
  const auto D = [&](int k) { return knot_d_[static_cast<std::size_t>(k + kD)]; };
  double ratio = 0, cross = 0;
  for (int k = -kD; k <= kD; ++k)
    for (int l = -kD; l <= kD; ++l) ratio += D(k) * D(l) * rho_row(k - l);
  const auto shared = [&](int lag) {  // E[G's noise at x times the left noise at x + lag] / vl
    double v = 0;
    for (int k = -kD; k <= kD; ++k) v += D(k) * rho_row(lag - k);
    return v;
  };
  for (int lag = -kD - kLag; lag <= kD + kLag; ++lag) cross -= shared(lag) * shared(-lag);
  grad_noise_ratio_ = ratio;
  grad_cross_ratio_ = cross;
  // kappa = sum_ij z_i z_j rho_ij / sum_i z_i^2 over the window, z the derivative regressor centred
  // on the window: the variance of the sandwich estimate over the white-noise one.
  float* z = chan_.data() + 4 * n;
  float* zz = chan_.data() + 6 * n;
  float* zh = chan_.data() + 7 * n;
  const Spans sp{span_lo_.data(), span_hi_.data(), w_, h_};
  for (int y = 0; y < h_; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * w_;
    dense_simd::centre_row(avx2_, ch + row, ch + 3 * n + row, S + 3 * n + row, S + row, z + row, zz + row,
                           zh + row, span_lo_[static_cast<std::size_t>(y)],
                           span_hi_[static_cast<std::size_t>(y)]);
  }
  // zh = z (rho * z), the correlation a 2D filter of z (zero outside the image), one lag at a time
  // over whole rows: plain multiply-adds the compiler vectorises.
  dense_simd::filter_lags(avx2_, z, zh, rho_.data(), kLag, sp);
  each4(sp, [&]<class T>(std::size_t i) { store(zh + i, load<T>(zh + i) * load<T>(z + i)); });
  float* szz = sums_.data() + 6 * n;
  float* szh = sums_.data() + 7 * n;
  dense_simd::box_sum(avx2_, zz, szz, scratch_.data(), sp, r_);
  dense_simd::box_sum(avx2_, zh, szh, scratch_.data(), sp, r_);
  for (int y = 0; y < h_; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * w_;
    dense_simd::kappa_row(avx2_, szz + row, szh + row, kappa_px_.data() + row,
                          span_lo_[static_cast<std::size_t>(y)], span_hi_[static_cast<std::size_t>(y)]);
  }
  std::size_t k = 0;
  sp.each([&](std::size_t i) {
    if (std::isfinite(d_[i]) && ch[i] > 0) line_copy_[k++] = kappa_px_[i];
  });
  if (k > 0) {
    kappa_ = kth_smallest(line_copy_.data(), k, k / 2, select_hist_);
  }
}

}  // namespace naneye::recon::scene
