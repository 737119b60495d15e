#pragma once
// The dense matcher on a rectified pair (rows are epipolar lines, d = u_left - u_right >= 0), its
// own unit so that it runs on any rectified images (the NanEye pair after dense_rectify, Middlebury's
// Aloe in the tests). docs/scene.md, "Dense path":
//   1. integer stage: our semi-global matcher (scene/sgm.hpp; Hirschmueller, PAMI 2008) over the
//      disparity band, census cost, five paths, its left-right check, no uniqueness or speckle
//      filter: the other decisions are ours, below;
//   2. sub-pixel: Gauss-Newton on the rectified pixels, every pixel's own window with a gain and an
//      offset between the eyes (L = a R(x - d) + b), linearised with the left's gradient (the
//      template's, which shares no noise with the right's samples), the right rows sampled by the cubic
//      B-spline (bspline.hpp: Keys' cubic, until 2026-12-06, biased the step towards whole pixels), each
//      pixel of the window warped by its own disparity (so slanted surfaces keep their shape); the window
//      sums are box filters, so every pixel costs the same;
//   3. sigma per pixel from the fit: s^2 (A^-1)_dd (A the normal matrix, both regressors' noise
//      taken out; s^2 the window's residual variance, floored at the median of windows of its
//      kind), times the correlation factor of the residual noise measured on the pair itself
//      (interpolation and a Bayer filter make neighbouring pixels' noise correlated);
//   4. validity: refinement converged near the integer stage; sigma small enough that the integer
//      stage's half-pixel basin holds at 3 sigma; the residual consistent with the pair's noise
//      (a chi-square test against the median window); a left-right check (the integer stage's: the
//      right view's disparities from the same aggregated cost must agree); not occluded (no nearer
//      surface claims the same right pixel); every tap inside both eyes' valid masks.
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

namespace naneye::recon::scene {

class Sgm;

// What disparity() and sigma() hold where there is no match.
inline constexpr float kNoMatch = std::numeric_limits<float>::quiet_NaN();

struct MatcherSettings {
  int min_disparity = 0;     // px; smallest disparity searched
  int num_disparities = 48;  // px; band width (a multiple of 16: the SGM's vector width)
  // SGM penalties (Hirschmueller 2008, Eq. 13) in the cost's unit, bits of the 3 x 3 block's summed
  // 5 x 5 census distance (0 .. 216; a wrong match costs ~12 bits a pixel, a right one on this
  // camera's noise 2-4): P1 = 2 bits a pixel lets a slanted surface step by 1 px, P2 = 8 bits a
  // pixel (~ the right-wrong gap) holds the disparity across a texture-poor stretch. Chosen on
  // bench_scene and Aloe (docs/scene.md).
  int sgm_p1 = 2 * 9;
  int sgm_p2 = 8 * 9;
  // px; the sub-pixel window (2 r + 1)^2: the smallest the matcher uses and the first it tries. r = 3
  // is best on sharp images (the simulator's presets, Middlebury Aloe: at r = 4 Aloe's coverage fell
  // 42.4 -> 36.2 %); on the real NanEye's blur (1.0 px) a larger window matches more (docs/scene.md).
  int radius = 3;
  // px; the largest window the matcher may choose per pair (RectifiedMatcher::radius_used; below).
  // max_radius == radius: the window fixed at radius, as before the choice existed. At the measured
  // sensor's blur every pair grows to the cap, and a larger window sums more gradient but spans more
  // of a curved surface, a misfit its sigma does not state: the measured tube's rms(err/sigma) is
  // 1.13 at 5, 1.22 at 6, 1.37 at 7 against the 1.4 (bench_dense_sigma --real-sensor
  // --max-radius N). 6 keeps that margin and covers 1.9-2.7 points more of the measured plane,
  // sphere, tube and height field than 5 (docs/scene.md, "The cap on the window"); of the sharp
  // presets only the Bayer tube grows past 5 (+3.7 points), and Middlebury Aloe keeps 3.
  int max_radius = 6;
  // The choice, from the pair alone. When more than grow_share of the candidates fail the sigma bound
  // (MatchCounts::texture: the fit's own statement that the window holds too little gradient for its
  // noise), the pair is matched again one radius larger, and the larger window is kept only if it
  // gives more than (1 + min_gain) times the valid pixels; on while the share stays above. The radius
  // carries over to the next pair (no second match in the steady state); it shrinks by one when the
  // sigmas predict that one radius smaller would refuse less than shrink_share (validate: sigma ~
  // 1 / (2 r + 1)) and the smaller window's valid count is not beaten by min_gain. A trial that loses
  // waits retry_pairs pairs before the next. Measured at r = 3, 2 renders per preset (bench_scene
  // --refusals), the sigma bound refuses of the candidates: simulator mono 0.6-2.0 % (tube 9.9 %),
  // Bayer 4.4-7.4 % (tube 22.6 %); Middlebury Aloe 6.3 %; the real NanEye's blur, mono 9.6-16.0 %
  // (tube 21.7 %), Bayer 17.7-22.3 % (tube 32.5 %). 8 % lies between the sharp and the blurred
  // (the sharp tube is tried: the valid count decides). Shrinking is tried below 7 %: a radius the
  // smaller window would not have left (at 5 % a Bayer height field kept the r = 4 it inherited from
  // the tube before it, 0.3 points less coverage); the gap to 8 % and the trial's own comparison keep
  // a pair near the bound from alternating. min_gain 2 %: the valid count's change from r to r + 1
  // on a blurred render is +9..66 % (r = 3 -> 4), ~0.5-3 % (4 -> 5); on Aloe it falls (r = 4: -15 %).
  double grow_share = 0.08;
  double shrink_share = 0.07;
  double min_gain = 0.02;
  int retry_pairs = 16;  // pairs (the NanEye's ~40 pairs a second: 0.4 s)
  int iterations = 4;    // Gauss-Newton steps (each pixel converges in 2-3 from the SGM's start)
  // The integer stage is trusted to +-0.5 px: a match whose disparity sigma exceeds a third of
  // that could sit in the wrong basin undetected (3 sigma).
  double max_sigma_px = 0.5 / 3;
  // Refinement may move a pixel this far from the integer stage (its 1/16 px parabola is within
  // 0.5 px of the truth when right); further means it slid to another minimum.
  double max_shift_px = 1.0;
  // Residual test: a window whose residual variance exceeds the median window's by the chi-square
  // upper quantile at this probability (its effective degrees of freedom) is not the same surface.
  double residual_p = 1e-3;
  // px; left-right check (sgm.hpp: the right view's integer disparity against both roundings of the
  // left's, within t - 1). 2, not cv::StereoSGBM's customary 1: with the census cost the right view,
  // the argmin of S along a diagonal, compares different left pixels' S, whose levels follow their
  // texture's contrast, and lands one further pixel off more often; at 1 px the check refused 3x as
  // many pixels as SGBM's did (plane: 12 058 against 3 864) and cost 10 points of coverage for no
  // lower bad-5 (docs/scene.md). The later tests (shift, residual, occlusion) keep bad-5 as it was.
  double lr_tolerance_px = 2.0;
  double occlusion_px = 1.0;  // px; a nearer surface claiming the same right pixel by more
  // Smallest share of the window's pixels that must carry data (near the domain's edges).
  double min_window_share = 0.5;
};

// Why pixels have no disparity, one pair (each pixel counted at the first test it fails).
struct MatchCounts {
  int candidates = 0;  // pixels with left data
  int no_integer = 0;  // the integer stage gave none (the band leaves the right image)
  int window = 0;      // too few window pixels with data in both eyes, or a singular fit
  int shift = 0;       // refinement slid more than max_shift_px from the integer stage
  int texture = 0;     // sigma above max_sigma_px
  int converged = 0;   // the reference field still moving by more than sigma
  int residual = 0;    // residual above the pair's noise (chi-square)
  int left_right = 0;  // the integer stage's left-right check refused it (counted before the tests below)
  int band_edge = 0;   // the integer stage's best lay on an edge the band was narrowed at (set_band)
  int occluded = 0;    // a nearer surface claims the same right pixel
  int valid = 0;
  int radius = 0;  // px; the sub-pixel window's radius this pair was matched with
};

// The residual test's null: a window's residual variance over the median of its kind is chi-square
// over nu (nu = (N - 3) / kappa for the pair's noise). A Bayer pair's demosaicing misfit, which
// varies with the texture's phase against the mosaic from window to window, widens that spread
// beyond the noise's (measured 2026-12-04: at p = 1e-3 the test refused 10-12 % of a Bayer
// render's windows, 1-2 % of a mono one's, and the refused windows' depths were no worse). So the
// spread is also read off the pair: its 15.87 % quantile (one sigma below the median) against the
// median, where wrong matches and occlusions, which only raise a residual, do not reach. Under
// Wilson-Hilferty (Johnson, Kotz, Balakrishnan 1994, Eq. 18.24) (q / m)^(1/3) = 1 - sqrt(c) / (1 - c)
// with c = 2 / (9 nu); solved for c, nu = 2 / (9 c). Infinity when q >= m or q <= 0 (no spread).
inline constexpr double kResidualLowerQuantile = 0.1587;
double effective_dof(double q, double median);

// A disparity band of the integer stage: [min_disparity, min_disparity + num_disparities).
struct DisparityBand {
  int min_disparity = 0, num_disparities = 0;
};

// The band that holds the disparities [lo, hi] found elsewhere (the pair's sparse points) widened by
// margin_px either side, rounded up to the SGM's 16 and centred on them, inside `whole`; `whole`
// itself when that is no narrower or lo, hi are not finite (DenseSettings::band_from_sparse).
DisparityBand band_around(double lo, double hi, double margin_px, const DisparityBand& whole);

class RectifiedMatcher {
 public:
  RectifiedMatcher(int width, int height, const MatcherSettings& s = {});
  ~RectifiedMatcher();
  // left, right: CV_32FC1 (width x height) luminance in any linear unit; valid_*: CV_8UC1, non-zero
  // where the eye has data. Results in disparity() / sigma() (CV_32FC1, NaN = no match).
  void match(const cv::Mat& left, const cv::Mat& right, const cv::Mat& valid_left,
             const cv::Mat& valid_right);
  // The disparity band of the next pairs' integer stage, inside the settings' band (num a multiple
  // of 16); the settings' band until called. A pixel whose integer best lies on an edge the band was
  // narrowed at has no match (MatchCounts::band_edge). Allocates nothing.
  void set_band(int min_disparity, int num_disparities);
  int band_min() const;
  int band_size() const;
  const cv::Mat& disparity() const { return disp_; }
  const cv::Mat& sigma() const { return sigma_; }
  // The integer stage's result (its parabola; NaN where it gave none, +infinity where its best lay on
  // a narrowed band's edge), for comparisons.
  const cv::Mat& integer_stage() const { return integer_; }
  const MatchCounts& counts() const { return counts_; }
  double residual_sigma() const { return residual_sigma_; }  // median window's, input units
  double noise_correlation() const { return kappa_; }        // median correlation factor
  const MatcherSettings& settings() const { return s_; }
  // px; the window radius the last pair was matched with (settings().radius .. max_radius), and
  // the one the next pair starts from.
  int radius_used() const { return r_; }

 private:
  void integer_stage(const cv::Mat& left, const cv::Mat& right);
  // refine() and validate() at radius r (r_ := r).
  void match_at(int r, const cv::Mat& left, const cv::Mat& valid_left);
  // The per-pair choice of the window (MatcherSettings::grow_share; dense_radius.cpp).
  void choose_radius(const cv::Mat& left, const cv::Mat& valid_left);
  // One pair's results, kept while another radius is tried (swapped, never copied or allocated).
  struct Result {
    cv::Mat disp, sigma;
    MatchCounts counts;
    double residual_sigma = 0, kappa = 1;
    int marginal = 0;
  };
  void swap_result(Result& r);
  void refine(const cv::Mat& left, const cv::Mat& valid_left);
  void validate(const cv::Mat& valid_left);
  void gather(const cv::Mat& left, bool last);
  void correlation(const cv::Mat& valid_left);
  void reference_detail();
  const float* window_detail();
  void update_spans(const cv::Mat& valid_left);
  // What the sub-pixel step reads of the right image, once per pair whatever the radii tried: its
  // rows' B-spline coefficients (right_spline_) and the taps' validity (taps_ok_).
  void prepare_right(const cv::Mat& right, const cv::Mat& valid_right);
  // The left image's gradient along the rows (left_grad_), once per pair (dense_subpixel.cpp).
  void left_gradient(const cv::Mat& left, const cv::Mat& valid_left);
  void level_medians(float min_n);
  void window_features(std::size_t i, float f[2]) const;
  int bin_of(const float f[2]) const;
  double expected_dof(std::size_t i) const;
  double expected_residual(std::size_t i) const;
  // The last fit's (A^-1)_cc with both regressors' noise taken out of A (dense_match.cpp).
  double eiv_zc(std::size_t i) const;

  // Residual variance per kind of window, 8 x 8 bins of (mean level, log contrast): shot noise is
  // linear in the level, the misfit grows with contrast; 64 bins still hold ~1000 windows each on
  // a 250 x 250 pair; a bin with fewer than 20 windows has no median worth testing against (the
  // frame's median is used).
  static constexpr int kBinsPerAxis = 8;
  static constexpr int kBins = kBinsPerAxis * kBinsPerAxis;
  static constexpr int kMinPerBin = 20;
  std::array<float, kBins> bin_median_{};
  // The degrees of freedom the bin's residuals show (effective_dof: from the spread of the lower
  // half, which wrong matches do not reach); the residual test uses no more than these.
  std::array<float, kBins> bin_nu_{};
  std::vector<float> features_;    // per window: mean level, log contrast (window_features)
  std::vector<std::uint8_t> bin_;  // per window: its bin
  float bin_lo_[2] = {0, 0}, bin_step_[2] = {1, 1};
  double global_median_ = 0;
  double global_nu_ = 0;

  MatcherSettings s_;
  int w_, h_;
  int r_;             // px; the window radius in use (the settings' radius .. max_radius)
  int wait_ = 0;      // pairs until the next trial of another radius (MatcherSettings::retry_pairs)
  int marginal_ = 0;  // candidates that passed the sigma bound but would fail it at r_ - 1 (validate)
  Result alt_;        // the other radius's results during a trial
  std::unique_ptr<Sgm> sgm_;
  cv::Mat integer_;
  cv::Mat disp_, sigma_;
  // Per pixel: the Gauss-Newton state (disparity, gain, offset, last step times gain, residual
  // variance, noise correlation factor, window count, (A^-1)_cc, the last fit's centred sums Sww,
  // Swg, Sgg for its errors-in-variables sigma) and the window sums (channel-major planes of w * h).
  std::vector<float> d_, a_, b_, c_, s2_, kappa_px_, n_, z_, smooth_step_, sww_, swg_, sgg_;
  MatchCounts counts_;
  std::vector<float> chan_, sums_, line_;
  std::vector<float> scratch_, line_copy_;
  double mean_ = 0;
  std::vector<float> rho_;  // the residual's autocorrelation over lags [-3, 3]^2
  // Per rectified row, the columns [span_lo_, span_hi_) from the first to the last pixel with left
  // data (empty: lo = hi = 0). The channel planes (chan_) are written only inside them and kept
  // zero outside, so the window sums, which read across them, need no other bounds. The other
  // per-pixel planes (sums_, n_, a_, b_, c_, s2_, z_, ...) keep stale values of earlier pairs
  // outside the spans: nothing may read them there.
  std::vector<int> span_lo_, span_hi_;
  // The right image's rows as cubic B-spline coefficients, each run of valid pixels on its own
  // (bspline.hpp): what the sub-pixel step samples.
  std::vector<float> right_spline_;
  // The left image's gradient along the rows: the derivative of its cubic B-spline interpolant at
  // the pixels (bspline_knot_derivative_tap), each run of valid pixels on its own; NaN where a
  // pixel or either neighbour has no data. The fit's gradient regressor (dense_subpixel.cpp).
  std::vector<float> left_grad_;
  std::array<double, 25> knot_d_{};                // bspline_knot_derivative_tap(-12 .. 12)
  std::vector<std::uint8_t> taps_ok_;              // right pixels whose 4 cubic taps are all valid
  bool avx2_ = false;                              // the plane kernels' 8-float versions (dense_simd.hpp)
  std::array<std::uint32_t, 4096> select_hist_{};  // the medians' counts (scene/select.hpp)
  double residual_sigma_ = 0, kappa_ = 1;
  // The left gradient's noise variance per the left pixels' (sum_kl D_k D_l rho(k - l)), and the
  // share of it the residual shares at the neighbouring pixels (-sum_m e(m) e(-m), e = D * rho),
  // both for the pair's measured noise correlation rho along the rows (correlation(), eiv_zc).
  double grad_noise_ratio_ = 1.392, grad_cross_ratio_ = 1.392;
};

}  // namespace naneye::recon::scene
