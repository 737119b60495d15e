// The rectified matcher's integer stage and its window radius per pair (dense_match.hpp); the
// sub-pixel step is in dense_subpixel.cpp, the validity decisions in dense_validate.cpp.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "../corners/simd.hpp"
#include "naneye/recon/scene/bspline.hpp"
#include "naneye/recon/scene/dense_match.hpp"
#include "sgm.hpp"

namespace naneye::recon::scene {
namespace {

// f(x, n) for every run of n consecutive non-zero entries of valid[0 .. w) starting at x: a row's
// spline is prefiltered one run at a time, so that no pixel beyond the mask reaches a coefficient.
template <class F>
void each_valid_run(const std::uint8_t* valid, int w, F&& f) {
  for (int x = 0; x < w;) {
    if (!valid[x]) {
      ++x;
      continue;
    }
    int end = x;
    while (end < w && valid[end]) ++end;
    f(x, end - x);
    x = end;
  }
}

SgmSettings sgm_settings(const MatcherSettings& s) {
  SgmSettings g;
  g.min_disparity = s.min_disparity;
  g.num_disparities = s.num_disparities;
  g.p1 = s.sgm_p1;
  g.p2 = s.sgm_p2;
  // The check compares the right view's integer disparity with both roundings of the left's
  // (passing if either is within lr_max_diff): the bracket adds up to 1 px, so a tolerance of t px
  // on the disparity is lr_max_diff = t - 1 (cv::StereoSGBM's disp12MaxDiff, the same rule).
  g.lr_max_diff = std::max(0, static_cast<int>(std::lround(s.lr_tolerance_px)) - 1);
  return g;
}
}  // namespace

double effective_dof(double q, double median) {
  if (!(q > 0) || !(median > q)) return std::numeric_limits<double>::infinity();
  const double u = 1.0 - std::cbrt(q / median);                       // sqrt(c) / (1 - c)
  const double r = (std::sqrt(1.0 + 4.0 * u * u) - 1.0) / (2.0 * u);  // sqrt(c)
  return 2.0 / (9.0 * r * r);
}

DisparityBand band_around(double lo, double hi, double margin_px, const DisparityBand& whole) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || hi < lo) return whole;
  const int a = static_cast<int>(std::floor(lo - margin_px)), b = static_cast<int>(std::ceil(hi + margin_px));
  const int need = (b - a + 1 + 15) / 16 * 16;
  if (need >= whole.num_disparities) return whole;
  const int first = std::clamp(a - (need - (b - a + 1)) / 2, whole.min_disparity,
                               whole.min_disparity + whole.num_disparities - need);
  return {first, need};
}

RectifiedMatcher::RectifiedMatcher(int width, int height, const MatcherSettings& s)
    : s_(s), w_(width), h_(height), r_(s.radius) {
  s_.max_radius = std::max(s_.radius, s_.max_radius);
  sgm_ = std::make_unique<Sgm>(w_, h_, sgm_settings(s_));
  const std::size_t n = static_cast<std::size_t>(w_) * h_;
  integer_.create(h_, w_, CV_32FC1);
  disp_.create(h_, w_, CV_32FC1);
  sigma_.create(h_, w_, CV_32FC1);
  if (s_.max_radius > s_.radius) {
    alt_.disp.create(h_, w_, CV_32FC1);
    alt_.sigma.create(h_, w_, CV_32FC1);
  }
  for (auto* v : {&d_, &a_, &b_, &c_, &s2_, &kappa_px_, &n_, &z_, &smooth_step_, &sww_, &swg_, &sgg_})
    v->assign(n, 0.f);
  chan_.assign(10 * n, 0.f);
  sums_.assign(10 * n, 0.f);
  line_.assign(2 * static_cast<std::size_t>(std::max(w_, h_) + 1), 0.f);
  scratch_.assign(n, 0.f);
  line_copy_.assign(n, 0.f);
  rho_.assign(49, 0.f);  // lags [-3, 3]^2 (dense_subpixel.cpp)
  span_lo_.assign(static_cast<std::size_t>(h_), 0);
  span_hi_.assign(static_cast<std::size_t>(h_), 0);
  avx2_ = simd::has_avx2();
  features_.assign(2 * n, 0.f);
  bin_.assign(n, 0);
  taps_ok_.assign(n, 0);
  right_spline_.assign(n, 0.f);
  left_grad_.assign(n, 0.f);
  static_assert(std::tuple_size_v<decltype(knot_d_)> == 2 * kKnotDerivativeReach + 1);
  for (int k = -kKnotDerivativeReach; k <= kKnotDerivativeReach; ++k)
    knot_d_[static_cast<std::size_t>(k + kKnotDerivativeReach)] = bspline_knot_derivative_tap(k);
}

RectifiedMatcher::~RectifiedMatcher() = default;

void RectifiedMatcher::match(const cv::Mat& left, const cv::Mat& right, const cv::Mat& valid_left,
                             const cv::Mat& valid_right) {
  CV_Assert(left.type() == CV_32FC1 && right.type() == CV_32FC1 && left.cols == w_ && left.rows == h_);
  update_spans(valid_left);
  prepare_right(right, valid_right);
  left_gradient(left, valid_left);
  integer_stage(left, right);
  match_at(r_, left, valid_left);
  if (s_.max_radius > s_.radius) choose_radius(left, valid_left);
}

void RectifiedMatcher::set_band(int min_disparity, int num_disparities) {
  sgm_->set_band(min_disparity, num_disparities);
}
int RectifiedMatcher::band_min() const {
  return sgm_->band_min();
}
int RectifiedMatcher::band_size() const {
  return sgm_->band_size();
}

void RectifiedMatcher::match_at(int r, const cv::Mat& left, const cv::Mat& valid_left) {
  r_ = r;
  refine(left, valid_left);
  validate(valid_left);
}

// The window's radius per pair (MatcherSettings::grow_share). The sigma bound's refusals are the fit's
// own statement that the window holds too little texture against the noise: blur (the real NanEye's
// 1.0 px) lowers the gradients and raises them, a larger window sums more gradient. But a larger
// window also spans more depth structure (Aloe's edges: fewer valid pixels, more bad ones), so
// the larger radius must prove itself on the pair: more valid pixels by min_gain. No ground truth:
// the valid count is what the validity tests (shift, sigma, residual, left-right, occlusion) pass.
void RectifiedMatcher::choose_radius(const cv::Mat& left, const cv::Mat& valid_left) {
  if (wait_ > 0) {
    --wait_;
    return;
  }
  const double candidates = std::max(1, counts_.candidates);
  int step = 0;
  if (counts_.texture > s_.grow_share * candidates && r_ < s_.max_radius)
    step = 1;
  else if (r_ > s_.radius && counts_.texture + marginal_ < s_.shrink_share * candidates)
    step = -1;  // one radius smaller would refuse few: the scene has sharpened
  while (step != 0) {
    const int from = r_;
    swap_result(alt_);  // alt_: this radius's result
    match_at(from + step, left, valid_left);
    const int larger = step > 0 ? counts_.valid : alt_.counts.valid;
    const int smaller = step > 0 ? alt_.counts.valid : counts_.valid;
    if ((larger > (1 + s_.min_gain) * smaller) != (step > 0)) {
      swap_result(alt_);  // the trial lost: back to the result at `from`, no trial for a while
      r_ = from;
      wait_ = s_.retry_pairs;
      return;
    }
    // Grown: on while the sigma bound still refuses too many; shrunk: one step a pair.
    if (step < 0 || r_ >= s_.max_radius || counts_.texture <= s_.grow_share * candidates) return;
  }
}

void RectifiedMatcher::swap_result(Result& r) {
  cv::swap(disp_, r.disp);
  cv::swap(sigma_, r.sigma);
  std::swap(counts_, r.counts);
  std::swap(residual_sigma_, r.residual_sigma);
  std::swap(kappa_, r.kappa);
  std::swap(marginal_, r.marginal);
}

// The fit's gradient regressor (dense_subpixel.cpp): the derivative of the left row's cubic B-spline
// interpolant at its pixels, (c[x + 1] - c[x - 1]) / 2 of its coefficients (bspline.hpp), every run
// of valid pixels on its own. Exact for a band-limited texture where the central difference of the
// pixels loses a third of the slope at 4 px wavelengths (and 4 Gauss-Newton steps then no longer
// converge on a sharp texture: measured, bench_dense_snr). NaN where the pixel or a neighbour has no
// data: such a pixel has no gradient to stand behind and stays out of every window (gather).
void RectifiedMatcher::left_gradient(const cv::Mat& left, const cv::Mat& valid_left) {
  float* c = line_.data();
  for (int y = 0; y < h_; ++y) {
    const float* l = left.ptr<float>(y);
    const std::uint8_t* v = valid_left.ptr<std::uint8_t>(y);
    float* g = left_grad_.data() + static_cast<std::size_t>(y) * w_;
    std::fill(g, g + w_, kNoMatch);
    each_valid_run(v, w_, [&](int x, int n) {
      if (n < 3) return;
      bspline_coefficients_line(l + x, n, c);
      for (int k = 1; k + 1 < n; ++k) g[x + k] = 0.5f * (c[k + 1] - c[k - 1]);
    });
  }
}

// The sub-pixel step's target (gather): every run of valid right pixels on its own, so that nothing
// beyond the valid mask (the fold, the band's empty columns) reaches a coefficient; and the pixels
// whose four cubic taps all lie inside that mask.
void RectifiedMatcher::prepare_right(const cv::Mat& right, const cv::Mat& valid_right) {
  for (int y = 0; y < h_; ++y) {
    const float* r = right.ptr<float>(y);
    const std::uint8_t* v = valid_right.ptr<std::uint8_t>(y);
    float* out = right_spline_.data() + static_cast<std::size_t>(y) * w_;
    std::copy_n(r, w_, out);  // invalid pixels: never a tap of a valid sample (taps_ok_)
    each_valid_run(v, w_, [&](int x, int n) {
      if (n >= 2) bspline_coefficients_line(r + x, n, out + x);
    });
  }
  // The taps' test 16 pixels at a time (SSE2 vectors): as a plain loop its four branches per pixel
  // were most of the ~3 M instructions a pair the sub-pixel step's two masks cost.
  using VB16 = std::uint8_t __attribute__((vector_size(16)));
  for (int y = 0; y < h_; ++y) {
    const std::uint8_t* vr = valid_right.ptr<std::uint8_t>(y);
    std::uint8_t* ok = taps_ok_.data() + static_cast<std::size_t>(y) * w_;
    auto one = [&](int x) {
      ok[x] = x >= 1 && x + 2 < w_ && vr[x - 1] && vr[x] && vr[x + 1] && vr[x + 2] ? 1 : 0;
    };
    int x = 0;
    for (; x < std::min(1, w_); ++x) one(x);
    for (; x + 18 <= w_; x += 16) {  // taps x - 1 .. x + 17 inside the row
      VB16 t[4];
      for (int k = 0; k < 4; ++k) std::memcpy(&t[k], vr + x - 1 + k, sizeof t[k]);
      const VB16 all = reinterpret_cast<VB16>((t[0] != 0) & (t[1] != 0) & (t[2] != 0) & (t[3] != 0)) & 1;
      std::memcpy(ok + x, &all, sizeof all);
    }
    for (; x < w_; ++x) one(x);
  }
}

void RectifiedMatcher::update_spans(const cv::Mat& valid_left) {
  const std::size_t n = static_cast<std::size_t>(w_) * h_;
  for (int y = 0; y < h_; ++y) {
    const std::uint8_t* vl = valid_left.ptr<std::uint8_t>(y);
    int lo = 0, hi = w_;
    while (lo < w_ && !vl[lo]) ++lo;
    while (hi > lo && !vl[hi - 1]) --hi;
    if (lo == hi) lo = hi = 0;
    const auto k = static_cast<std::size_t>(y);
    // Another mask than the last pair's (the rig's is the same on every pair): what was written
    // inside the old span and lies outside the new one would be read as data.
    for (int x = span_lo_[k]; x < span_hi_[k]; ++x)
      if (x < lo || x >= hi)
        for (int c = 0; c < 10; ++c)
          chan_[c * n + k * static_cast<std::size_t>(w_) + static_cast<std::size_t>(x)] = 0.f;
    span_lo_[k] = lo;
    span_hi_[k] = hi;
  }
}

void RectifiedMatcher::integer_stage(const cv::Mat& left, const cv::Mat& right) {
  // On the float images (census needs no 8-bit scale), the left data's spans only.
  sgm_->run(left, right, span_lo_.data(), span_hi_.data(), integer_);
}

}  // namespace naneye::recon::scene
