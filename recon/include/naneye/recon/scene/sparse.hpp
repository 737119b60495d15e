#pragma once
// Sparse scene reconstruction (docs/scene.md): Shi-Tomasi features spread over the left
// raw frame, matched along the exact model's epipolar curve in the right raw frame (ZNCC), refined
// on the raw pixels by affine inverse-compositional LK, checked right-to-left, triangulated with
// niter2 + reprojection refinement (triangulation.hpp), each with the depth sigma its own match
// precision gives. A feature whose match leaves a model's domain is flagged, never triangulated.
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "naneye/recon/camera/rig.hpp"
#include "naneye/recon/corners/detector.hpp"
#include "naneye/recon/geometry/calibration_uncertainty.hpp"
#include "naneye/recon/scene/epipolar_match.hpp"
#include "naneye/recon/scene/feature_ids.hpp"
#include "naneye/recon/scene/features.hpp"
#include "naneye/recon/scene/lk_affine.hpp"

namespace naneye::recon::scene {

struct SparseSettings {
  FeatureSettings features;
  LkSettings lk;
  double z_min_mm = 5, z_max_mm = 150;  // mm; the depths searched (the scenes: 8-80 mm)
  double search_step_px = 1.0;          // px; curve sampling of the coarse search
  int search_radius = 3;                // px; coarse ZNCC window (7 x 7)
  double min_zncc = 0.7;                // coarse best below: no match
  // Ambiguity: the best must leave (1 - best) <= this share of (1 - second best) (a texture that
  // repeats along the curve gives two near-equal peaks: refused instead of guessed).
  double max_ambiguity = 0.5;
  // After LK a match is kept when its ZNCC reaches min_final_zncc, or else when its residual is the
  // two images' noise: SSR <= q (N - 8) 2 sigma_n^2, q the upper final_noise_false_reject quantile of
  // chi-square(N - 8) / (N - 8) (N the window's pixels, 8 the warp's and the normalisation's
  // parameters, sigma_n the left image's measured noise: features.hpp). A fixed ZNCC asks for a
  // signal-to-noise ratio (0.9: texture variance >= 9x the noise's) that a real NanEye's blurred
  // low-contrast texture does not reach while its match is right; the residual test asks only that
  // nothing but noise is left. A wrong match leaves the texture's variance in the residual. 0: off.
  double min_final_zncc = 0.9;
  double final_noise_false_reject = 1e-3;
  // The coarse search (ZNCC along the epipolar curve, both ways) on a mono luminance through the 3x3
  // binomial, the filter a Bayer luminance already has; detection, the LK refinement and its sigma
  // stay on the unfiltered pixels (least squares on white noise: the filter cannot make them more
  // precise, and its correlated noise would need the sandwich). Why: a real NanEye's edges are
  // 1.0-1.6 px wide (../shared/notes/measurements.md), so its optics pass < 1 % of the contrast at
  // 0.5 cycles/px (Gaussian MTF exp(-2 pi^2 sigma^2 f^2) at sigma 1.0) and ~29 % at 0.25, where the
  // binomial keeps 0 and 50 %: it removes the noise of a band that holds no signal, and the noise
  // variance falls to 0.14x. A mono render at the measured sensor (bench_scene --real-sensor,
  // --refusals): the tube's coarse ZNCC fell below min_zncc on 164 of its ~390 features per pair.
  bool search_binomial = true;
  // The widest LK window (docs/scene.md, "Sparse path" step 5), px: 21 x 21 against lk.radius's
  // 9 x 9 (5.4x the pixels: ~0.45x the disparity sigma where the texture is even). A wider window's
  // match replaces the narrower one's only where the affine warp holds over it (sparse_wide.cpp);
  // 0 (or <= lk.radius): never. At most kMaxLkRadius (10); the reconstructor refuses more. 13 x 13
  // until 2026-12-07; 21 x 21 with the nesting below: at the measured sensor, fixed pattern
  // removed, the planes' depth error 0.32 -> 0.26 % (mono), 0.31 -> 0.23 % (Bayer), the height
  // field's unchanged, for ~2x the sparse path's time (docs/scene.md, "The nested widening").
  int wide_radius = 10;
  // px; the window widens from lk.radius to wide_radius by rings this wide (9 -> 13 -> 17 -> 21),
  // each step's match held to the three tests against the step before it and kept only if every
  // narrower step was: a plane goes on to the widest, a curved surface stops where its misfit shows.
  // Without the curvature model (curvature_radius_px 0) one step straight to 21 x 21 tests its fit
  // against the 9 x 9 one's noise, which hides the misfit a test against 17 x 17 shows (the
  // sphere: rms(err/sigma) 2.14 at 21 x 21 in one step); with it, the one step holds (wide_direct).
  int wide_step = 2;
  // true (with the curvature model on and a ladder of two steps or more): each feature first tries
  // the widest window in one step from lk.radius, and only where that step's tests refuse it climbs
  // the nested ladder above, up to the ring below the widest. A plane's features mostly pass and
  // pay one wide fit instead of three; a curved surface's fall back and stop where their misfit
  // shows. Measured against the ladder for every feature: the sparse path ~0.7x the time, its
  // error the same or lower in every bench_scene condition (docs/scene.md, "One step first").
  bool wide_direct = true;
  // Each of the wider window's three tests (its outer ring's residual against the narrow window's
  // noise, its shift against the narrow one's, and that shift test pooled over the neighbourhood;
  // sparse_wide.cpp) refuses this share of the features where the affine holds: the price is their
  // ~1.4x larger sigma, against a bias the tests then miss.
  double wide_false_reject = 0.01;
  // px; the neighbourhood whose wider windows' shift tests are pooled (sparse_wide.cpp). A curved
  // surface biases the wide windows on it alike, by a noncentrality of ~0.7 per feature on the
  // height preset (its mean statistic 1.7 against 1), invisible to one feature's test; k features
  // pooled see it at 0.7 k / sqrt(2 k) sigma, so k >~ 60 for both 1 % errors at 2.3 sigma each.
  // ~34 features lie within 32 px; measured on height mono, rms(err/sigma) 1.55 at 32 px, 1.33 at
  // 64, 1.27 (the narrow window's own) at 96, while the planes keep all their wider windows.
  double wide_pool_radius_px = 96;
  // px; the neighbourhood whose 9 x 9 matches give a feature's curvature model (sparse_curvature.cpp):
  // the inverse depth's gradient and second derivatives over the left image, fitted as a quadric
  // through the other features' depths within this radius, give the second-order displacement an
  // affine warp leaves; it moves every window's match by a bias the LK reports per unit
  // (LkResult::curvature_gain). Where the curvature is significant the wider windows' shift tests
  // and matches are corrected by it and their variance takes the model's; where the quadric does
  // not follow the neighbourhood, no window wider than the narrow one. The radius trades the
  // model's noise against its reach: ~50 features lie within 28 px (7 px cells), and on a plane
  // the model's sd is then ~0.2 of a 21 x 21 match's sigma (0.5 at 21 px, 0.1 at 35 px, where the
  // quadric follows the height preset's waves less often). 0: no model (the shift tests alone).
  double curvature_radius_px = 28;
  double lr_tolerance_px = 1.0;  // px; right-to-left search must land this close to the feature
  // A point whose depth sigma exceeds this share of its depth is flagged `imprecise` instead of
  // given: 5 % of the depth would lie within its 3 sigma (the outlier line), so its depth is
  // not one to stand behind. Rare at the simulator's default sharpness (blur 0.41 px: 2 of 1536
  // points on plane-far); at a real NanEye's blur (edges 1.0-1.6 px; at 1.22 px ~20 % of
  // plane-far's points at 55-75 mm), where 2.2 % (mono) and 3.4 % (Bayer) of the points given
  // were more than 5 % off without it, 0.3 % and 0.15 % with it (docs/scene.md, "Blur").
  double max_depth_sigma_rel = 0.05 / 3;
  int max_features = 1536;
  // The valid points a pair needs: the issue's >= 300 good points per pair, with room for a scene
  // the right eye half misses. Features are tried coarse to fine over the image (one per 4 x 4
  // cells first, then per 2 x 2, then the rest; strongest first within each) and matching stops
  // once this many are valid, so the points stay spread over the whole view, the ones left out are
  // the least precise, and the time per pair stays bounded (docs/scene.md).
  int max_points = 512;
  FeatureIdSettings ids;
};

enum class PointStatus {
  ok,
  no_candidates,        // the epipolar curve has no usable window in the right image
  weak_match,           // best ZNCC below min_zncc (texture-less, or not seen by the right eye)
  ambiguous,            // two near-equal peaks along the curve
  refinement_failed,    // LK diverged, left the image or the right domain
  left_right_mismatch,  // the right-to-left search lands elsewhere
  triangulation_failed,
  imprecise,  // matched and triangulated, but its depth sigma is above max_depth_sigma_rel
};

const char* to_string(PointStatus s);

struct ScenePoint {
  std::int64_t id = 0;  // stable across pairs while the feature is followed (feature_ids.hpp)
  Eigen::Vector2d left_px{0, 0}, right_px{0, 0};  // raw pixels (right: NaN unless matched)
  Eigen::Vector3d X = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());  // left frame, mm
  double depth_sigma_mm = std::numeric_limits<double>::quiet_NaN();
  // The depth sigma the calibration allows at X (geometry/calibration_uncertainty.hpp): common to
  // every point of the pair, so it does not shrink when points are averaged. NaN unless valid and
  // the calibration carries its covariance.
  double calib_sigma_mm = std::numeric_limits<double>::quiet_NaN();
  double zncc = 0;
  // px; the radius of the LK window its match came from: lk.radius, or the widest step of the
  // nested widening it kept (SparseSettings::wide_step); 0 unless matched.
  int window_radius_px = 0;
  // px along the epipolar curve; the next wider window's match disagreed with this one's by more
  // than their noise allows (its shift test failed, sparse_wide.cpp), and depth_sigma_mm takes that
  // disagreement in; 0: no such test failed.
  double window_disagreement_px = 0;
  PointStatus status = PointStatus::no_candidates;
  bool valid() const { return status == PointStatus::ok; }
};

struct SparseResult {
  std::vector<ScenePoint> points;  // every feature tried, valid or not (reserved: max_features)
  double noise_sigma_dn = 0;       // the left image's measured noise
  int valid_count = 0;
};

// The luminance of both eyes and their usable masks; shared with the dense path.
struct StereoLuma {
  std::vector<float> left, right, scratch;
  // The coarse search's images (SparseSettings::search_binomial): the luminance through the 3x3
  // binomial when `search_filtered`, else unused (the search reads the luminance itself).
  std::vector<float> left_search, right_search;
  // The right luminance's cubic B-spline coefficients (bspline.hpp): the sub-pixel matcher's target.
  std::vector<float> right_spline;
  int width = 0, height = 0;
  bool bayer = false;  // filtered from a GRBG mosaic: neighbouring pixels share noise
  bool search_filtered = false;
  GrayView left_view() const { return {left.data(), width, height}; }
  GrayView right_view() const { return {right.data(), width, height}; }
  GrayView right_spline_view() const { return {right_spline.data(), width, height}; }
  GrayView left_search_view() const { return {(search_filtered ? left_search : left).data(), width, height}; }
  GrayView right_search_view() const {
    return {(search_filtered ? right_search : right).data(), width, height};
  }
};

class SparseReconstructor {
 public:
  explicit SparseReconstructor(const StereoRig& rig, const SparseSettings& s = {});
  // One pair; `out` keeps its capacity from pair to pair (allocation-free once warm).
  void reconstruct(const RawImageView& left, const RawImageView& right, SparseResult& out);
  // The same on luminance already computed (by load_luma).
  void reconstruct(const StereoLuma& luma, SparseResult& out);
  void load_luma(const RawImageView& left, const RawImageView& right);
  const StereoLuma& luma() const { return luma_; }
  const StereoRig& rig() const { return rig_; }
  const SparseSettings& settings() const { return s_; }
  // Non-zero where a window of `radius` around the pixel lies inside the camera's model domain and
  // the active image (column 249 and the edge rows excluded). eye 0 = left.
  const std::vector<std::uint8_t>& usable(int eye) const { return usable_[eye]; }
  // px; the nested widening's window radii beyond lk.radius, narrowest first (SparseSettings::wide_step).
  const std::vector<int>& wide_radii() const { return wide_radii_; }
  // A new sequence (source restarted, seek): the next pair's features all get new ids.
  void reset_ids() { ids_.reset(); }

 private:
  // LkResult::curvature_gain: a match's shift per unit of each second-order displacement term.
  using CurvatureGain = std::array<Eigen::Matrix2d, 3>;
  struct WideStep {
    double hausman = -1;  // its shift against the step before (chi-square, 1 dof); < 0: none
    double d_along = 0;   // that shift along the epipolar curve, less the curvature model's share, px
    bool tested = false;  // its fit converged: d and V below hold
    bool usable = false;  // passed its ring test and triangulated
    Eigen::Vector2d right_px{0, 0};
    Eigen::Vector3d X{0, 0, 0};
    double depth_sigma_mm = 0, zncc = 0;
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();  // of right_px, px^2
    // Its shift against the step before and that difference's covariance, px, px^2.
    Eigen::Vector2d d{0, 0};
    Eigen::Matrix2d V = Eigen::Matrix2d::Identity();
    CurvatureGain gain{};
    bool has_gain = false;  // LkResult::has_curvature_gain
  };
  // The widening's steps for one feature tried, narrowest first; `chosen`: how many choose_wide kept.
  // `direct`: the one step from the narrow window to the widest (SparseSettings::wide_direct),
  // `direct_kept` where choose_wide kept it; `w`, `A0`, `narrow`: the coarse inverse depth, the
  // predicted affine and the narrow fit, from which choose_wide climbs the ladder where it was not.
  struct WideCandidate {
    std::array<WideStep, kMaxLkRadius> step;
    int chosen = 0;
    WideStep direct;
    bool direct_kept = false;
    double w = 0;
    Eigen::Matrix2d A0 = Eigen::Matrix2d::Identity();
    LkResult narrow;
    // The covariance of the match the point holds (px^2): the narrow one's, then each chosen step's
    // after its curvature correction; a failed shift test widens it by the disagreement.
    Eigen::Matrix2d kept_cov = Eigen::Matrix2d::Zero();
    // The narrow window's gain. The right image's place of the feature's ray as a function F(q, w)
    // of the left pixel offset q and the inverse depth w (1/mm), at the coarse match: dF/dw (px mm,
    // the epipolar curve's tangent), d2F/dw2 and d2F/dw dq (sparse_curvature.cpp).
    CurvatureGain narrow_gain{};
    bool narrow_has_gain = false;  // LkResult::has_curvature_gain
    Eigen::Vector2d dpdw{0, 0}, d2pdw2{0, 0};
    Eigen::Matrix2d d2pdwdq = Eigen::Matrix2d::Zero();
    // The template shape's own map at the coarse depth, F(q, w0): its Jacobian dF/dq and second
    // derivatives (d2F/dc2, d2F/dc dr, d2F/dr2): the LK's affine acts on F's places, not on q.
    Eigen::Matrix2d dpdq = Eigen::Matrix2d::Identity();
    Eigen::Matrix<double, 2, 3> d2pdq2 = Eigen::Matrix<double, 2, 3>::Zero();
    // Where the neighbours fix it: the second-order displacement's three coefficient vectors c_m
    // (px / px^2; d_k = sum_m c_m (1/2 dc^2, dc dr, 1/2 dr^2)_m), their derivatives by the
    // neighbourhood's quadric parameters (the inverse depth's gradient and second derivatives, 1/mm
    // per px and px^2) and those parameters' covariance.
    // has_curvature: the model holds and corrects; curvature_misfit: the quadric does not follow
    // the neighbourhood (no widening); neither: no model (too few neighbours, or no curvature to
    // tell), the shift tests alone.
    bool has_curvature = false;
    bool curvature_misfit = false;
    Eigen::Matrix<double, 2, 3> c = Eigen::Matrix<double, 2, 3>::Zero();
    std::array<Eigen::Matrix<double, 2, 5>, 3> dc_dtheta{};
    Eigen::Matrix<double, 5, 5> theta_cov = Eigen::Matrix<double, 5, 5>::Zero();
    // The widest step that passed its own tests, or nullptr.
    const WideStep* widest() const {
      if (direct.usable) return &direct;
      const WideStep* w = nullptr;
      for (const WideStep& st : step)
        if (st.usable) w = &st;
      return w;
    }
  };
  // noise_sigma_dn: the left image's (SparseResult::noise_sigma_dn), for the final residual test.
  void match(const StereoLuma& luma, const Feature& f, double noise_sigma_dn, ScenePoint& p,
             WideCandidate& wc);
  bool triangulate_match(const Eigen::Vector2d& left_px, const Eigen::Vector2d& right_px,
                         const Eigen::Matrix2d& cov_px, Eigen::Vector3d& X, double& depth_sigma_mm) const;
  // The residual bound of a window of this radius within which its match's misfit is the noise
  // alone, per unit 2 sigma_n^2 (final_noise_false_reject); < 0: off.
  double ssr_noise_bound(int radius) const;
  // A converged fit of a window of this radius is a match: a ZNCC of min_final_zncc or more, or a
  // residual the noise explains (ssr_quantile_; faint texture, where the ZNCC alone refused the
  // measured sensor's tube).
  bool fit_accepted(const LkResult& fit, int radius, double noise_sigma_dn) const {
    const bool noise_left =
        fit.ssr_dn2 <= ssr_quantile_[static_cast<std::size_t>(radius)] * 2 * noise_sigma_dn * noise_sigma_dn;
    return fit.converged && (!(fit.zncc < s_.min_final_zncc) || noise_left);
  }
  // SparseSettings::max_depth_sigma_rel.
  bool precise(const Eigen::Vector3d& X, double depth_sigma_mm) const {
    return depth_sigma_mm <= s_.max_depth_sigma_rel * X.z();
  }
  void init_wide();
  // Each valid point takes its widest step's match whose neighbourhood's pooled shift test passes
  // at that step and every narrower one (sparse_wide.cpp).
  void choose_wide(const StereoLuma& luma, double noise_sigma_dn, SparseResult& out);
  // One step's tests over every feature that has it (kDirect: WideCandidate::direct); each valid
  // point that holds the step inside keeps this one where they pass.
  static constexpr int kDirect = -1;
  void choose_step(SparseResult& out, int k);
  // SparseSettings::wide_direct where it holds: the one step to the widest window needs the
  // curvature model (without it the sphere's misfit hides in the narrow window's noise) and a
  // ladder to fall back on.
  bool direct_first() const { return s_.wide_direct && s_.curvature_radius_px > 0 && wide_radii_.size() > 1; }
  // The LK settings of every fit of this pair (its noise kernel, the curvature gain).
  LkSettings lk_settings(bool bayer) const;
  // Each valid point's curvature model from its neighbours' narrow matches (sparse_curvature.cpp).
  void fit_curvature(SparseResult& out);
  // wc's model from the neighbourhood's quadric (its parameters a, g, H and their covariance),
  // where its curvature is distinguishable from none.
  void set_curvature_model(WideCandidate& wc, const Eigen::Matrix<double, 6, 1>& theta,
                           const Eigen::Matrix<double, 6, 6>& cov) const;
  // F's derivatives at the feature (WideCandidate), from the exact model.
  void displacement_derivatives(const Feature& f, double w, WideCandidate& wc) const;
  // A match corrected by its curvature bias (wc's model, `gain`): right_px less the bias, cov plus
  // the model's share; re-triangulated into X and depth_sigma_mm. False: triangulation failed.
  bool correct_for_curvature(const WideCandidate& wc, const Eigen::Vector2d& left_px,
                             const CurvatureGain& gain, Eigen::Vector2d& right_px, Eigen::Matrix2d& cov,
                             Eigen::Vector3d& X, double& depth_sigma_mm) const;
  // A failed shift test (sparse_wide.cpp): p keeps its match, its depth sigma widened by the
  // disagreement d_along (px, along the curve).
  void disagree(const WideCandidate& wc, ScenePoint& p, double d_along) const;
  // The bias a window with this gain takes from wc's model, and the bias's Jacobian by the model's
  // parameters.
  static Eigen::Vector2d curvature_bias(const WideCandidate& wc, const CurvatureGain& gain,
                                        Eigen::Matrix<double, 2, 5>* jacobian = nullptr);
  // The nested widening of `narrow` over wide_radii_'s first `steps`, into wc, until a step fails
  // its own tests.
  void widen_steps(const StereoLuma& luma, const Feature& f, double w, const Eigen::Matrix2d& A0,
                   const LkSettings& lks, const LkResult& narrow, const Eigen::Vector2d& left_px,
                   double noise_sigma_dn, std::size_t steps, WideCandidate& wc);
  // A wider window's fit into st where it converged and triangulates (`usable`); false otherwise.
  bool take_fit(const LkResult& fit, const Eigen::Vector2d& left_px, WideStep& st) const;
  // Where each template pixel at Chebyshev distance in (skip, rad] from the feature lands in the
  // right image for a surface facing the camera at inverse depth w (exact model), relative to the
  // centre's place, row-major over the (2 rad + 1)^2 window.
  void predict_shape(const Feature& f, double w, int rad, int skip, Eigen::Vector2d* out) const;
  // The refinement of `narrow` (radius rn: the step before, wide_radii_[k - 1] or lk.radius; its
  // template shape inner_shape) to wide_radii_[k], where the feature's window fits and its ring
  // passes (sparse_wide.cpp), else not converged; its template shape into `shape`; into `st` its
  // shift against `narrow` and that shift's covariance (`tested`), for choose_wide's tests.
  LkResult widen(const StereoLuma& luma, const Feature& f, double w, const Eigen::Matrix2d& A0,
                 const LkSettings& lks, std::size_t k, int rn, const LkResult& narrow,
                 const Eigen::Vector2d* inner_shape, Eigen::Vector2d* shape, double noise_sigma_dn,
                 WideStep& st);

  StereoRig rig_;
  std::optional<CalibrationUncertainty> calib_;  // empty: the calibration has no covariance
  SparseSettings s_;
  Eigen::Matrix3d R_lr_, R_rl_;
  Eigen::Vector3d T_lr_, T_rl_;
  std::vector<std::uint8_t> usable_[2];         // LK window radius + 1
  std::vector<std::uint8_t> usable_search_[2];  // coarse window
  std::vector<int> wide_radii_;                 // the widening's steps, px (wide_step)
  // Per step: where its window fits (left: radius, right: + 1).
  std::vector<std::array<std::vector<std::uint8_t>, 2>> usable_wide_;
  double wide_z_ = 0;              // upper normal quantile of wide_false_reject
  double wide_chi1_ = 0;           // chi-square(1) upper quantile of wide_false_reject
  double wide_kappa_[2] = {1, 1};  // noise_dof_factor: mono, Bayer
  // The LK residual's noise bound per unit 2 sigma_n^2 (final_noise_false_reject; < 0: off), by
  // window radius: the narrow window's and each widening step's (ssr_noise_bound).
  std::array<double, kMaxLkRadius + 1> ssr_quantile_{};
  std::vector<WideCandidate> wide_;  // per feature tried
  std::vector<int> cell_point_;      // per feature cell: its point's index, or -1
  // cell_point_'s cell of a left pixel.
  std::size_t point_cell(const Eigen::Vector2d& px) const {
    const int cell = s_.features.cell_px, gw = (luma_.width + cell - 1) / cell;
    return static_cast<std::size_t>(static_cast<int>(px.y()) / cell * gw + static_cast<int>(px.x()) / cell);
  }
  // visit(j) for every point j in cell_point_ within `radius` px of `px` (a point there itself
  // included), cell rows in order: the neighbourhood the curvature model and the pooled test use.
  template <class Visit>
  void for_each_near(const SparseResult& out, const Eigen::Vector2d& px, double radius, Visit&& visit) const {
    const int cell = s_.features.cell_px, gw = (luma_.width + cell - 1) / cell;
    const int gh = static_cast<int>(cell_point_.size()) / gw,
              reach = static_cast<int>(std::ceil(radius / cell));
    const int cx = static_cast<int>(px.x()) / cell, cy = static_cast<int>(px.y()) / cell;
    for (int y = std::max(0, cy - reach); y <= std::min(gh - 1, cy + reach); ++y)
      for (int x = std::max(0, cx - reach); x <= std::min(gw - 1, cx + reach); ++x) {
        const int j = cell_point_[static_cast<std::size_t>(y * gw + x)];
        if (j >= 0 && (out.points[static_cast<std::size_t>(j)].left_px - px).squaredNorm() <= radius * radius)
          visit(static_cast<std::size_t>(j));
      }
  }
  std::vector<std::uint8_t> noise_mask_;  // left: 3x3 neighbourhood inside usable_search_[0]
  StereoLuma luma_;
  FeatureDetector detector_;
  std::vector<Feature> features_;
  FeatureIds ids_;
  std::vector<std::int64_t> id_scratch_;
  EpipolarCurve curve_, back_curve_;
  std::vector<double> rays_;  // left pixel centres' normalized rays (x, y)
  // The same rays turned into the right camera's frame, R (x, y, 1), as three planes (x, y, z): the
  // LK shape (predict_shape) needs X_r = R ray z + T at ~170 pixels per feature, and R ray is fixed.
  std::vector<double> right_rays_;
  std::vector<float> inv_norm_[2];              // per pixel: 1 / |window - mean| of the coarse window
  std::vector<double> norm_scratch_;            // scratch of window_inverse_norms
  std::vector<Eigen::Vector2d> shape_;          // the LK template's predicted places in the right image
  std::vector<Eigen::Vector2d> shape_wide_[2];  // the same for the widening's steps, alternately
};

}  // namespace naneye::recon::scene
