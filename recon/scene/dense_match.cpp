// The rectified matcher's integer stage and its validity decisions (dense_match.hpp); the
// sub-pixel step is in dense_subpixel.cpp.
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>

#include "naneye/recon/corners_noise.hpp"
#include "naneye/recon/scene/dense_match.hpp"

namespace naneye::recon::scene {
namespace {
constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

cv::Ptr<cv::StereoSGBM> make_sgbm(const MatcherSettings& s) {
  // P1, P2: the penalties OpenCV documents for 8-bit images (8 and 32 x channels x block area);
  // no uniqueness, left-right or speckle filtering: validity is decided after the sub-pixel step.
  const int area = s.sgm_block * s.sgm_block;
  return cv::StereoSGBM::create(s.min_disparity, s.num_disparities, s.sgm_block, 8 * area, 32 * area, -1, 0,
                                0, 0, 0, cv::StereoSGBM::MODE_SGBM_3WAY);
}
}  // namespace

RectifiedMatcher::RectifiedMatcher(int width, int height, const MatcherSettings& s)
    : s_(s), w_(width), h_(height) {
  sgbm_l_ = make_sgbm(s_);
  // The mirrored pair (right image first, both flipped) gives the right view's disparities with
  // the same band.
  sgbm_r_ = make_sgbm(s_);
  const std::size_t n = static_cast<std::size_t>(w_) * h_;
  l8_.create(h_, w_, CV_8UC1);
  r8_.create(h_, w_, CV_8UC1);
  l8f_.create(h_, w_, CV_8UC1);
  r8f_.create(h_, w_, CV_8UC1);
  d16_.create(h_, w_, CV_16SC1);
  d16r_.create(h_, w_, CV_16SC1);
  sgbm_.create(h_, w_, CV_32FC1);
  sgbm_right_.create(h_, w_, CV_32FC1);
  disp_.create(h_, w_, CV_32FC1);
  sigma_.create(h_, w_, CV_32FC1);
  for (auto* v : {&d_, &a_, &b_, &c_, &s2_, &kappa_px_, &n_, &z_}) v->assign(n, 0.f);
  chan_.assign(10 * n, 0.f);
  sums_.assign(10 * n, 0.f);
  line_.assign(2 * static_cast<std::size_t>(std::max(w_, h_) + 1), 0.f);
  scratch_.assign(n, 0.f);
  line_copy_.assign(n, 0.f);
  acc_.assign(static_cast<std::size_t>(std::max(w_, h_)), 0.0);
  rho_.assign(25, 0.f);
}

RectifiedMatcher::~RectifiedMatcher() = default;

void RectifiedMatcher::match(const cv::Mat& left, const cv::Mat& right, const cv::Mat& valid_left,
                             const cv::Mat& valid_right) {
  CV_Assert(left.type() == CV_32FC1 && right.type() == CV_32FC1 && left.cols == w_ && left.rows == h_);
  integer_stage(left, right, valid_left, valid_right);
  refine(left, right, valid_left, valid_right);
  validate(valid_left);
}

void RectifiedMatcher::integer_stage(const cv::Mat& left, const cv::Mat& right, const cv::Mat& valid_left,
                                     const cv::Mat& valid_right) {
  // SGBM wants 8 bits: both eyes on one scale, the brightest valid pixel at 255 (the pair's own
  // range, whatever the exposure).
  double lo = 0, hi_l = 0, hi_r = 0;
  cv::minMaxLoc(left, &lo, &hi_l, nullptr, nullptr, valid_left);
  cv::minMaxLoc(right, &lo, &hi_r, nullptr, nullptr, valid_right);
  const double scale = 255.0 / std::max({hi_l, hi_r, 1e-6});
  left.convertTo(l8_, CV_8U, scale);
  right.convertTo(r8_, CV_8U, scale);
  sgbm_l_->compute(l8_, r8_, d16_);
  cv::flip(r8_, l8f_, 1);
  cv::flip(l8_, r8f_, 1);
  sgbm_r_->compute(l8f_, r8f_, d16r_);
  const int invalid = (s_.min_disparity - 1) * 16;
  for (int y = 0; y < h_; ++y) {
    const short* dl = d16_.ptr<short>(y);
    const short* dr = d16r_.ptr<short>(y);
    float* ol = sgbm_.ptr<float>(y);
    float* orr = sgbm_right_.ptr<float>(y);
    for (int x = 0; x < w_; ++x) {
      ol[x] = dl[x] <= invalid ? kNan : dl[x] / 16.f;
      const short v = dr[w_ - 1 - x];
      orr[x] = v <= invalid ? kNan : v / 16.f;
    }
  }
}

void RectifiedMatcher::validate(const cv::Mat& valid_left) {
  const std::size_t n = static_cast<std::size_t>(w_) * h_;
  const int side = 2 * s_.radius + 1;
  const float min_n = static_cast<float>(s_.min_window_share * side * side);
  // The median window's residual variance: the pair's noise as the fit sees it (interpolation and
  // demosaicing included), against which each window's residual is tested.
  std::size_t m = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (std::isfinite(d_[i]) && n_[i] >= min_n && s2_[i] > 0) scratch_[m++] = s2_[i];
  double med = 0;
  if (m > 0) {
    std::nth_element(scratch_.begin(), scratch_.begin() + static_cast<long>(m / 2),
                     scratch_.begin() + static_cast<long>(m));
    med = scratch_[m / 2];
  }
  residual_sigma_ = std::sqrt(med);
  const double zq = upper_normal_quantile(s_.residual_p);
  for (int y = 0; y < h_; ++y) {
    const std::uint8_t* vl = valid_left.ptr<std::uint8_t>(y);
    const float* sg = sgbm_.ptr<float>(y);
    const float* sr = sgbm_right_.ptr<float>(y);
    float* od = disp_.ptr<float>(y);
    float* os = sigma_.ptr<float>(y);
    for (int x = 0; x < w_; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w_ + x;
      od[x] = kNan;
      os[x] = kNan;
      const float d = d_[i];
      if (!vl[x] || !std::isfinite(d) || !std::isfinite(sg[x]) || n_[i] < min_n || !(a_[i] > 0)) continue;
      if (std::abs(d - sg[x]) > s_.max_shift_px) continue;
      const double sigma = std::sqrt(std::max(0.f, kappa_px_[i]) * s2_[i] * z_[i]) / a_[i];
      if (!(sigma <= s_.max_sigma_px) || std::abs(c_[i] / a_[i]) > std::max(sigma, 1e-3)) continue;
      // Chi-square upper quantile over the window's effective degrees of freedom (Wilson-Hilferty
      // cube approximation; Johnson, Kotz, Balakrishnan 1994, Eq. 18.24).
      const double nu = std::max(1.0, (n_[i] - 3.0) / std::max(1.0, static_cast<double>(kappa_px_[i])));
      const double t = 1 - 2 / (9 * nu) + zq * std::sqrt(2 / (9 * nu));
      if (s2_[i] > med * t * t * t) continue;
      // Left-right: the right view's own disparity at the match.
      const int xr = static_cast<int>(std::lround(x - d));
      if (xr < 0 || xr >= w_ || !std::isfinite(sr[xr]) || std::abs(sr[xr] - d) > s_.lr_tolerance_px) continue;
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
      const int xr = static_cast<int>(std::lround(x - od[x]));
      if (xr >= 0 && xr < w_) best[xr] = std::max(best[xr], od[x]);
    }
    for (int x = 0; x < w_; ++x) {
      if (!std::isfinite(od[x])) continue;
      const int xr = static_cast<int>(std::lround(x - od[x]));
      if (xr < 0 || xr >= w_ || best[xr] > od[x] + s_.occlusion_px) {
        od[x] = kNan;
        sigma_.ptr<float>(y)[x] = kNan;
      }
    }
  }
}

}  // namespace naneye::recon::scene
