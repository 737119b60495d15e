#pragma once
// Checkerboard inner-corner detection on raw NanEye frames: a coarse grid (tracked from
// the previous frame, or a full search), then a sub-pixel fit of every corner with a blurred-saddle
// model whose edges are straight in undistorted coordinates (corners/refine.hpp), then validation
// of the whole grid. Positions are raw (distorted) pixels, pixel centres at integers as in OpenCV.
//
// Never a false corner: a grid that fails any check gives found == false and no corners.
#include <array>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "naneye/recon/camera/camera_model.hpp"
#include "naneye/recon/camera/undistort_map.hpp"
#include "naneye/recon/corners/coarse_grid.hpp"
#include "naneye/recon/corners/fast_fit.hpp"
#include "naneye/recon/corners/noise.hpp"
#include "naneye/recon/corners/refine.hpp"
#include "naneye/recon/geometry/board.hpp"
#include "naneye/recon/pair/result.hpp"

namespace naneye::recon {

// A defect pixel lies beyond all its same-site neighbours by this much (raw_to_luminance).
inline constexpr float kDefectThresholdDn = 60.0f;

enum class PixelLayout : std::uint8_t { mono, bayer_grbg };

// A raw frame as the driver delivers it (driver::Frame::pixels): 10-bit values, row-major. recon
// does not depend on the driver, hence a plain view. Column 249 of a NanEye frame is padding and
// row 0 / row 249 carry reference pixels: pixels in `ignore_last_cols` columns and the first and last
// `ignore_edge_rows` rows are never used.
struct RawImageView {
  const std::uint16_t* data = nullptr;
  int width = 250, height = 250, stride = 250;  // stride in elements
  PixelLayout layout = PixelLayout::mono;
  int ignore_last_cols = 1;
  int ignore_edge_rows = 1;
};

// Per-corner flags (bit set).
enum CornerFlag : std::uint8_t {
  kCornerBeyondFold = 1,  // outside the camera model's valid domain: position from a pixel-space fit
  kCornerFitPoor = 2,     // the saddle fit converged but its residual or contrast is marginal
  kCornerNearEdge = 4,    // the fit window had to be shrunk at the image border
};

struct Corner {
  Eigen::Vector2d px{0, 0};  // raw pixel, centres at integers
  int row = 0, col = 0;      // id = row * cols + col
  std::uint8_t flags = 0;
  double sigma_px = 0;        // fitted blur of the edges
  double contrast = 0;        // |white - black| at the corner, in DN
  double residual = 0;        // RMS fit residual, DN
  double position_se_px = 0;  // standard error of px for the frame's noise (least squares), px
  // Fitted edge directions (radians, in undistorted local pixel coordinates) - reused when tracking.
  double theta_row = 0, theta_col = 0;
  SaddleShading shading{};  // the fit's linear terms at px - reused when tracking
};

struct CornerResult {
  bool found = false;
  bool tracked = false;  // true when the grid came from the previous result (no full search)
  int rows = 0, cols = 0;
  int count = 0;  // rows * cols when found, else 0
  std::array<Corner, kMaxCorners> corners{};
  const Corner& at(int row, int col) const { return corners[static_cast<std::size_t>(row * cols + col)]; }
};

// Why the last detection found nothing (diagnostics; `naneye recon` may log it).
enum class CornerFailure : std::uint8_t {
  none,
  bad_input,     // image size differs from the camera's, or the pattern exceeds kMaxCorners
  no_grid,       // the full search found no rows x cols grid
  fit_failed,    // a corner's saddle fit diverged or its window left the image
  fit_rejected,  // a corner's residual or blur is beyond what the noise and the model explain
  low_contrast,  // a corner's contrast is below min_contrast_snr noise sigmas (too dark, too flat)
  polarity,      // the corners do not alternate like a checkerboard
  not_planar,    // the grid is not the image of a plane (homography residual too large)
  track_moved    // tracking only: a corner moved too far (full search follows)
};
const char* to_string(CornerFailure f);

// The corner that made the last detection fail with fit_rejected or low_contrast (diagnostics).
struct CornerRejection {
  int index = -1;                 // row-major id in the coarse grid's order
  double rms = 0, bound_rms = 0;  // the fit's RMS residual and what the noise and misfit allow, DN
  double contrast = 0, noise_sigma = 0, level = 0, sigma_px = 0, radius_px = 0;
  double position_se_px = 0;  // the position's standard error for the frame's noise (px)
};

struct CornerSettings {
  BoardGeometry board;  // the pattern looked for (its inner corners; square_mm is not used here)
  // Fit window radius (pixels, Chebyshev): a fraction of the local corner spacing, within bounds.
  double window_fraction = 0.55;
  double min_radius = 2.5, max_radius = 7.0;  // max_radius <= 8 (fit_saddle's work space)
  // The first of the two fits per corner (from the coarse or previous grid) uses at most this radius.
  double first_pass_radius = 4.0;
  // Acceptance of a corner's fit, against the frame's own noise (corners/noise.hpp, docs/corners.md
  // "Decisions"). The residual must be what the noise and the model's own misfit explain:
  //   rms^2 <= var_n (1 + z sqrt(2 / nu)) + (model_misfit |b|)^2,
  // var_n the luminance's noise variance at the corner's level, nu the window's degrees of freedom
  // (pixels - parameters, divided by the Bayer filter's noise correlation), z the standard normal
  // quantile of residual_false_reject (the chi-square's upper tail, Wilson-Hilferty's normal form),
  // |b| half the black-white difference.
  double residual_false_reject = 1e-3;  // a pure-noise window is refused with this probability
  // The model's misfit (Gaussian PSF, pixel centres sampled, straight edges) as a fraction of |b|:
  // 3.7 % at the 99.9th percentile of bench_corners' corners (noise included); 8-13 % on real
  // photographs (OpenCV's sample stereo set: JPEG blocks and ringing, a PSF that is no Gaussian).
  double model_misfit = 0.15;
  // A corner whose misfit (beyond the noise, as a share of |b|) exceeds both poor_misfit and
  // poor_per_median times its frame's median misfit is flagged kCornerFitPoor: the model describes
  // it worse than the simulator's 99.9th percentile (3.7 %) and worse than this frame's typical
  // corner. The frame's share matters where the imaging chain misfits every corner alike (JPEG
  // blocks and ringing: a median of 6-13 % on OpenCV's photographs, whose corners are still 0.05 px
  // from cornerSubPix's); 1.5: the worst corner of those frames is 1.19-1.66x its median, so the few
  // above 1.5x are the frame's outliers. Downstream does not use flagged corners.
  double poor_misfit = 0.05;
  double poor_per_median = 1.5;
  // The contrast (white - black) at least this many noise standard deviations: a step that noise
  // crosses on one pixel in ~1000 (3 sigma each side), i.e. a board plainly visible.
  double min_contrast_snr = 6.0;
  // Blur bounds (px): below min_sigma_px the erf is a step and its gradient vanishes (the fit's
  // numerical floor); above radius / max_sigma_per_radius the window no longer holds the edge
  // profile's +-2.5 sigma.
  double min_sigma_px = 0.05, max_sigma_per_radius = 0.4;
  // ... unless the window cannot be larger (a far board: squares of 4-6 px) and the fit still holds
  // the corner to the noise: its position's standard error (least squares, the frame's noise) within
  // this (px; a returned corner is false beyond 0.5 px: 5 standard errors). Such corners, and any
  // corner whose standard error exceeds this, are flagged kCornerFitPoor.
  double max_position_se_px = 0.1;
  // Boards whose squares are at most this many pixels across (the grid's smaller step) are also fitted
  // as the blurred checkerboard's fundamental (corners/sine_fit.hpp) over harmonic_window_steps of a
  // step each side, and the fit whose corner has the smaller standard error among those accepted is
  // kept. 8 px: at the real sensor's ~1-1.3 px blur the third harmonic there keeps >= 17 % of the
  // fundamental's amplitude, a misfit the residual test refuses, so larger squares gain nothing
  // and are left to the X-junction fit alone.
  double harmonic_max_spacing_px = 8.0;
  double harmonic_window_steps = 1.25;
  // Grid validation: the RMS of a homography fit from board to undistorted coordinates, in pixels
  // (scaled by fx), and the worst single corner.
  double max_homography_rms_px = 0.5, max_homography_worst_px = 1.5;
  // Tracking: accept the tracked grid when every corner moved less than this from the previous one.
  double max_track_motion_px = 4.0;
  // Full search: our saddle lattice (corners/coarse_grid.hpp). OpenCV's findChessboardCorners (then
  // findChessboardCornersSB) only when ours finds no grid and this is on: it costs ~4 ms per eye and
  // allocates on every call, and ours finds every board the benchmark and tests render.
  CoarseGridSettings coarse;
  bool opencv_fallback = false;
  // The fit's 8-lane kernels when the CPU has AVX2 + FMA; off: the SSE2 baseline every x86-64 runs
  // (benchmarks compare both).
  bool allow_avx2 = true;
};

class CornerDetector {
 public:
  CornerDetector(const CameraModel& camera, const CornerSettings& settings = {});

  // Detects the board in `image`. With `previous` found, first tracks from it (fit windows around the
  // previous corners) and falls back to a full search when tracking fails validation.
  // Returns out.found. Allocates nothing once warmed up (except inside the optional OpenCV fallback).
  bool detect(const RawImageView& image, const CornerResult* previous, CornerResult& out);
  // Full search only (no tracking).
  bool detect_full(const RawImageView& image, CornerResult& out) { return detect(image, nullptr, out); }

  const CameraModel& camera() const { return camera_; }
  const CornerSettings& settings() const { return settings_; }
  CornerFailure last_failure() const { return failure_; }
  const CornerRejection& last_rejection() const { return rejection_; }
  // The luminance image of the last detect() call (float DN, width x height), for diagnostics. After
  // a tracked detection only the board's rows are current (tracking computes no others).
  const std::vector<float>& luminance() const { return luma_; }
  // The last frame's noise model (of its luminance: the Bayer filter's variance factor applied) and
  // white balance.
  const NoiseModel& noise() const { return noise_; }
  const CfaBalance& cfa_balance() const { return balance_; }
  // The residual variance a fit of `fit` may have (see CornerSettings), DN^2; and its contrast bound.
  double residual_bound(const SaddleFit& fit, double radius, double misfit) const;
  bool fit_acceptable(const SaddleFit& fit, double radius) const;
  // The standard error of a fitted corner's position (px) for the frame's noise.
  double position_se(const SaddleFit& fit) const;

 private:
  // This level's detection: tracking from `previous`, else a full search.
  bool detect_here(const RawImageView& image, const CornerResult* previous, CornerResult& out);
  // The next pyramid level's (half_): the frame binned 2 x 2, its corners scaled back to this level.
  bool detect_half(const RawImageView& image, bool track_previous, CornerResult& out);
  bool track(const CornerResult& previous, CornerResult& out, bool band);
  std::pair<int, int> tracking_rows(const CornerResult& previous) const;  // [first, last + 1)
  bool full_search(CornerResult& out);
  bool refine_all(CornerResult& out, bool from_previous);
  double fit_radius(double spacing) const;
  // The blur test: within the window's reach, beyond it but the corner held to the noise (flagged
  // poor), or refused.
  enum class BlurVerdict : std::uint8_t { held, poor, refused };
  BlurVerdict blur_verdict(const SaddleFit& fit, double radius) const;
  bool fit_corner(const SaddleInit& init, const EdgeDirections* edges, double radius, double tolerance_px,
                  SaddleFit& fit, std::uint8_t& flags);
  // A far board's corner: the harmonic fit (see harmonic_max_spacing_px) replaces `fit` when it is
  // accepted and holds the corner better; `radius` becomes its window's. True when replaced.
  bool prefer_harmonic(const Eigen::Vector2d& px, const Eigen::Vector2d& dc, const Eigen::Vector2d& dr,
                       int row, int col, int rows, int cols, double tolerance_px, SaddleFit& fit,
                       double& radius);
  void grid_edges(const std::array<Eigen::Vector2d, kMaxCorners>& px, int rows, int cols);
  bool validate(const CornerResult& out);
  void luminance_and_noise(const RawImageView& image, int row_lo, int row_hi);
  void mark_clipped(const RawImageView& image, int row_lo, int row_hi);
  // The frame's luminance with its usable area and, when any, the clip mark (read by the fits only).
  LumaView luma_view() const;

  CameraModel camera_;
  CornerSettings settings_;
  int width_ = 0, height_ = 0;
  CornerFailure failure_ = CornerFailure::none;
  CornerRejection rejection_;
  NoiseModel noise_;  // of the luminance
  CfaBalance balance_;
  NoiseEstimator noise_estimator_;
  bool bayer_ = false;
  double z_reject_ = 0;                            // upper_normal_quantile(settings_.residual_false_reject)
  int row_begin_ = 0, row_end_ = 0, col_end_ = 0;  // usable pixel area
  std::vector<float> luma_, scratch_;
  std::vector<unsigned char> gray8_;
  // Bayer: nonzero where the luminance mixes a clipped site (LumaView::clipped); any_clipped_ false
  // when the frame's rows have none (the fit then skips the mark).
  std::vector<std::uint8_t> clipped_;
  bool any_clipped_ = false;
  std::vector<Eigen::Vector2f> coarse_;
  CoarseGridFinder coarse_finder_;
  // Built once per camera (shared by copies of the detector): raw pixel -> undistorted coordinates.
  std::shared_ptr<const UndistortMap> map_;
  std::vector<FastFitScratch> work_;  // one fit's work space (a vector: copies get their own)
  std::array<EdgeDirections, kMaxCorners> edges_{};
  // The next pyramid level, for boards whose squares outgrow this level's pixel scales (the saddle
  // map's ring of 3 px, fit windows of at most max_radius): empty when the half image would be
  // smaller than kMinLevelSide (detector.cpp), as for the NanEye's own 250 x 250 frames. A vector
  // so that copies of the detector get their own.
  std::vector<CornerDetector> half_;
  std::vector<std::uint16_t> half_raw_;
  CornerResult half_result_, half_previous_;
  bool from_half_ = false;      // the last board was found at the next level: track there first
  bool harmonic_used_ = false;  // the last refine_all fitted a corner as the fundamental (sine_fit)
};

// The luminance of a raw frame, without moving any edge: mono is copied; GRBG Bayer is filtered
// with the 3x3 binomial kernel, which weighs R, G, B as 1/4, 1/2, 1/4 at every site of the mosaic
// and is symmetric about each pixel centre (no half-pixel shift). (For comparison, OpenCV calls a
// GRBG sensor COLOR_BayerGB2GRAY = COLOR_BayerGRBG2GRAY.) Unusable pixels are replicated from their
// neighbours of the same Bayer site; isolated defect pixels (beyond all 8 same-site neighbours by
// more than defect_threshold_dn) are replaced by the neighbours' median. `out` and `scratch` must
// hold width * height floats each. Only rows [row_lo, row_hi) of `out` are sure to be computed
// (row_hi < 0: to the last row; up to 3 rows beyond may be written): tracking needs the board's only.
// With `balance` valid, a Bayer mosaic's sites are first mapped to G-equivalent values (white
// balance from the frame itself, estimate_cfa_balance) so that the luminance is a grey board's
// whatever the channel gains; `scratch` then holds that balanced mosaic (the noise is measured on it).
// `textured`: the frame may hold detail at the scale of the same-site spacing (2 px on a Bayer
// mosaic): texture seen through a sharp lens puts extremes beyond all same-site neighbours on ~0.5 %
// of a Bayer frame's pixels, and a far board's squares of ~4 px put every square's centre there (its
// same-site neighbours lie on the square's edges and corners), so a defect must then also stand
// apart from its immediate neighbours brought to its colour (luma.cpp, apart_from_its_texture). Hot,
// dead and stuck pixels still do. The corner detector and the scene paths set it; false keeps the
// same-site test alone (a board whose squares are many blurs across).
void raw_to_luminance(const RawImageView& image, float* out, float* scratch,
                      float defect_threshold_dn = kDefectThresholdDn, int row_lo = 0, int row_hi = -1,
                      const CfaBalance* balance = nullptr, bool textured = false);

// The 3x3 binomial [1 2 1; 2 4 2; 1 2 1] / 16 of a w x h image, rows [row_lo, row_hi) of `out`
// (`f` and `out` apart). On a GRBG mosaic it sums R, G, B with weights 1/4, 1/2, 1/4 at every site;
// on any image it is symmetric about the pixel centre, so edges do not move. Allocates nothing.
void binomial_3x3(const float* f, float* out, int w, int h, int row_lo, int row_hi);

// Orders a detected grid by one image-space convention so that two near-identical views number the
// same physical corners alike: the column axis (row 0 -> col 0 .. cols-1) points to +x in the image
// when it is closer to horizontal, else to +y. Only the 180-degree turn is free for rows != cols.
void canonical_order(CornerResult& r);

}  // namespace naneye::recon
